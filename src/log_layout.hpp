// The columns of a run file's /samples table and the views over them, for a model and the chosen
// groups (h5log.hpp describes the file).  One table of names and units, and the one function that
// lays a Sample out in that order, side by side so they cannot drift apart.  Internal.
#pragma once

#include "soadyn/h5log.hpp"

#include <string>
#include <vector>

namespace soadyn::log {

struct Column {
  std::string name, unit;
};

// A view of /samples' columns [first, first + cols·bodies): rank 1 (cols = 0: one column),
// rank 2 (T × cols) or rank 3 (T × bodies × cols, bodies > 0).
struct View {
  std::string path;  // "/q", "/energy/kinetic", "/bodies/position"
  int first = 0, cols = 0, bodies = 0;
  std::vector<std::string> units;  // one per column of the view's last dimension (/sensitivities: per element)
};

struct Layout {
  std::vector<Column> columns;
  std::vector<View> views;
  std::vector<std::string> groups;  // "/energy", "/momentum", "/bodies" as needed
};

Layout layout(const Model& model, const LogGroups& groups);

// appends one row: the sample's numbers in the order of layout(model, groups).columns; the
// frames' poses (groups.frames) are computed from s.q with `data` (kinematics frames only)
void append_row(const Model& model, Data& data, const LogGroups& groups, const Sample& s, std::vector<double>& row);

// SI units of q and v, one per column (joint_traits)
std::vector<std::string> q_units(const Model& model);
std::vector<std::string> v_units(const Model& model);

}  // namespace soadyn::log
