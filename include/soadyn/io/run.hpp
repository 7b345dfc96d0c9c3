// A scenario run from C++ in one call, as Python's soadyn.simulate:
//
//   soadyn::Scenario sc = soadyn::load_scenario("scenarios/double_pendulum.yaml");
//   soadyn::SimulateOptions o;
//   o.settings = sc.simulation;         // or leave it empty: the scenario's own settings
//   o.settings->t_end = 2.0;
//   o.output = "out/pendulum.h5";       // a run file too (optional)
//   soadyn::Trajectory tr = soadyn::simulate(sc, o);
//   if (!tr.summary.completed) ...      // a run that failed midway says so here
//
// Below it, simulate(sc, settings, observer, …) (simulate.hpp) streams samples to an observer and
// keeps none: for callers that write their own logs.
#pragma once

#include "soadyn/sim/controller.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/sim/simulate.hpp"
#include "soadyn/sim/trajectory.hpp"

#include <atomic>
#include <functional>
#include <limits>
#include <optional>
#include <string>

namespace soadyn {

struct SimulateOptions {
  // the run's settings; empty: the scenario's own (sc.simulation)
  std::optional<SimulationSettings> settings;
  // τ_c(t, q, v) added to the inputs' (controller.hpp), with the scenario's own controllers;
  // continuous, or sampled every settings.control_dt.  One that throws or returns a τ that is not
  // finite ends the run there (summary.status says when and why).
  ControlFunction controller;
  // also told every sample, event and the end (e.g. a caller's own log); nullptr: none
  RunObserver* observer = nullptr;
  // a run file to write as `soadyn run -o` does ("": none): checked before anything is touched
  // (output_file.hpp: never an input of the run, never a file another writer holds, an existing
  // file replaced only when it is a run file or with `force`), locked, built under a temporary
  // name and renamed into place at its first flush
  std::string output;
  bool force = false;
  // refuse a run whose file would take more bytes than this (the projected rows and stored model
  // files), as `soadyn run --max-output-size`
  double max_output_bytes = std::numeric_limits<double>::infinity();
  // false: keep no samples in the Trajectory (summary and warnings only), for long runs that only
  // write a file
  bool keep_samples = true;
  // ends the run before the next step once non-zero (a signal number, or −1), and a poll run
  // before every step that may set it (simulate.hpp)
  const std::atomic<int>* stop = nullptr;
  std::function<void()> poll;
};

// Runs sc with the options and returns its samples and summary.  Throws soadyn::Error before
// anything runs or any file is touched for settings, sensitivities or an output the run cannot
// take (check_run, check_sensitivities, output_file.hpp); IoError (h5log.hpp) when the run file
// cannot be written.  A run that fails midway does not throw: the Trajectory holds its samples up
// to there and summary.completed is false.
Trajectory simulate(const Scenario& sc, const SimulateOptions& options = {});

}  // namespace soadyn
