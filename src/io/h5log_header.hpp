// What H5Log writes once, when it creates a run file (h5log.hpp describes the file): the sources
// and the model, the /samples and /events tables, the groups' names and conventions, the views
// over /samples.  Each throws h5::Failure on a failed HDF5 call.  Internal.
#pragma once

#include "soadyn/io/h5log.hpp"

#include "h5_util.hpp"
#include "log_layout.hpp"

#include <hdf5.h>

#include <string>

namespace soadyn::log {

// the root attributes, /scenario, /robot (when the scenario named one) and /model_files (an MJCF model's)
void write_sources(hid_t file, const Scenario& sc, const std::string& version, const LogGroups& groups);

// /model: names and units of every column of q and v, the joints, the tree, the conventions
void write_model(hid_t file, const Model& m);

// /samples, the table every series is a view of (T × W, chunks of about 64 KiB), with its columns' names and units
h5::Id create_samples(hid_t file, const Layout& lay);

// /events, the joint limits' events, 7 numbers a row (E × 7)
h5::Id create_events(hid_t file);

// the layout's groups, and /bodies', /frames' and /sensitivities' names and conventions when logged
void write_groups(hid_t file, const Layout& lay, const Model& m, const LogGroups& logged);

// every view of the layout over /samples' `width` columns
void create_views(hid_t file, const Layout& lay, int width);

}  // namespace soadyn::log
