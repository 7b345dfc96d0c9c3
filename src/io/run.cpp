// simulate(sc, options): a run in one call, its samples kept as a Trajectory and, if asked, a run
// file written as `soadyn run -o` writes it.
#include "soadyn/io/run.hpp"

#include "soadyn/io/h5log.hpp"
#include "soadyn/io/output_file.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/io/version.hpp"

#include <cstdio>
#include <memory>

namespace soadyn {

namespace {

// Forwards to two observers (the log, then the caller's); either may be absent.
class Both : public RunObserver {
 public:
  Both(RunObserver* a, RunObserver* b) : a_(a), b_(b) {}
  void on_sample(const Sample& s) override {
    if (a_) a_->on_sample(s);
    if (b_) b_->on_sample(s);
  }
  void on_event(const LimitEvent& e) override {
    if (a_) a_->on_event(e);
    if (b_) b_->on_event(e);
  }
  void on_progress(const RunSummary& r) override {
    if (a_) a_->on_progress(r);
    if (b_) b_->on_progress(r);
  }
  void on_finish(const RunSummary& r) override {
    if (a_) a_->on_finish(r);
    if (b_) b_->on_finish(r);
  }

 private:
  RunObserver *a_, *b_;
};

// Refuses a run file larger than the options allow: the rows the run logs and the MJCF model's
// files it stores.
void check_output_size(const Scenario& sc, const SimulationSettings& s, const LogGroups& groups, double limit) {
  double stored = 0;
  for (const ModelFile& f : sc.model_files) stored += double(f.data.size());
  const double rows = output_rows(s), row = double(row_bytes(sc.model, logged_groups(sc, s, groups)));
  const double bytes = rows * row + stored;
  if (bytes <= limit) return;
  char buf[240];
  std::snprintf(buf, sizeof buf, ": the output would take %.6g bytes (%.6g rows of %.0f bytes, %.0f bytes of model files), "
                "more than max_output_bytes %.6g", bytes, rows, row, stored, limit);
  throw Error(buf);
}

}  // namespace

Trajectory simulate(const Scenario& sc, const SimulateOptions& o) {
  const SimulationSettings settings = o.settings ? *o.settings : sc.simulation;
  // everything is checked before any file is touched, as `soadyn run` does
  std::vector<std::string> warnings = check_run(sc, settings);
  check_sensitivities(sc, settings, bool(o.controller));
  {
    System probe(sc.model, sc.inputs, settings.dynamics);
    make_integrator(settings.method, probe, settings, 0.0, probe.state(sc.q0, sc.v0));
  }
  std::unique_ptr<OutputLock> lock;  // declared first: held until the log is closed
  std::unique_ptr<H5Log> log;
  if (!o.output.empty()) {
    LogGroups groups;
    groups.control = bool(o.controller);
    try {
      check_output_size(sc, settings, groups, o.max_output_bytes);
    } catch (const Error& e) {
      throw Error(o.output + e.what());
    }
    std::vector<std::string> inputs = sc.files;  // every file the scenario was read from
    inputs.push_back(sc.path);
    check_output_path(o.output, OutputKind::Run, inputs, o.force);
    lock = std::make_unique<OutputLock>(o.output);
    log = std::make_unique<H5Log>(o.output, sc, settings, version(), groups);
  }
  Both out(log.get(), o.observer);
  TrajectoryRecorder recorder(&out);
  RunObserver* first = o.keep_samples ? static_cast<RunObserver*>(&recorder) : &out;
  RunSummary summary = simulate(sc, settings, first, nullptr, o.stop, o.poll, o.controller);
  log.reset();  // closes the file before anyone may read it
  lock.reset();

  Trajectory tr = recorder.take(sc.model, sc.inputs.prescribed, sc.inputs.loops);
  tr.summary = std::move(summary);
  warnings.insert(warnings.end(), tr.summary.warnings.begin(), tr.summary.warnings.end());
  tr.warnings = std::move(warnings);
  return tr;
}

}  // namespace soadyn
