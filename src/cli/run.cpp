#include "cli.hpp"

#include "soadyn/h5log.hpp"
#include "soadyn/integrators.hpp"
#include "soadyn/simulate.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdlib>

#include <chrono>
#include <cstdio>
#include <filesystem>

namespace soadyn::cli {

namespace {
// a positive finite number, said plainly
const CLI::Validator kPositive(
    [](std::string& text) {
      char* end = nullptr;
      const double x = std::strtod(text.c_str(), &end);
      if (text.empty() || *end != '\0' || !(x > 0) || !std::isfinite(x))
        return "expected a positive number, got '" + text + "'";
      return std::string();
    },
    "POSITIVE");
}  // namespace

void add_run(CLI::App& app, RunOptions& o) {
  CLI::App* c = app.add_subcommand(
      "run",
      "Simulate a scenario and log states, energy and momentum to HDF5.\n"
      "Command-line values override the scenario's 'simulation' section.\n"
      "Exit status: 0 completed, 2 bad input, 3 the run failed (the file keeps what was logged).");
  c->add_option("SCENARIO", o.scenario, "scenario file (.yaml)")->required();
  c->add_option("-o,--output", o.output, "HDF5 output file (default out/<scenario name>.h5)");
  c->add_option("--method", o.method, join(integrator_names(), " | "))->check(CLI::IsMember(integrator_names()));
  c->add_option("--rtol", o.rtol, "CVODE relative tolerance")->check(kPositive);
  c->add_option("--atol", o.atol, "CVODE absolute tolerance")->check(kPositive);
  c->add_option("--dt", o.dt, "fixed-step methods' step, s")->check(kPositive);
  c->add_option("--t-end", o.t_end, "end time, s")->check(kPositive);
  c->add_option("--output-dt", o.output_dt, "time between logged samples, s")->check(kPositive);
  c->add_flag("-q,--quiet", o.quiet, "no summary on stdout");
}

namespace {

// a progress bar on stderr when it is a terminal and the run has taken over a second
class Progress : public RunObserver {
 public:
  Progress(RunObserver* next, double t_end) : next_(next), t_end_(t_end), tty_(isatty(2)) {}
  void on_sample(const Sample& s) override {
    if (next_) next_->on_sample(s);
  }
  void on_progress(const RunSummary& r) override {
    if (next_) next_->on_progress(r);
    const auto now = std::chrono::steady_clock::now();
    if (!tty_ || now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const int width = 40, done = int(width * std::min(1.0, r.t_reached / t_end_));
    std::fprintf(stderr, "\r[%.*s%*s] t = %.3f / %.3f s", done, "########################################", width - done, "",
                 r.t_reached, t_end_);
    shown_ = true;
  }
  void on_finish(const RunSummary& r) override {
    if (shown_) std::fprintf(stderr, "\r%*s\r", 80, "");
    if (next_) next_->on_finish(r);
  }

 private:
  RunObserver* next_;
  double t_end_;
  bool tty_, shown_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

}  // namespace

int run_simulation(const RunOptions& o) {
  const Scenario sc = load_scenario(o.scenario);
  SimulationSettings s = sc.simulation;
  if (o.method) s.method = *o.method;
  if (o.rtol) s.rtol = *o.rtol;
  if (o.atol) s.atol = *o.atol;
  if (o.dt) s.dt = *o.dt;
  if (o.t_end) s.t_end = *o.t_end;
  if (o.output_dt) s.output_dt = *o.output_dt;
  const std::string out = o.output.empty() ? "out/" + sc.name + ".h5" : o.output;

  check_run(sc, s);                        // refuses before any output file exists
  H5Log log(out, sc, s, SOADYN_VERSION);  // refuses an unwritable path before the run starts
  Progress progress(&log, s.t_end);
  const RunSummary r = simulate(sc, s, &progress);

  if (!o.quiet) {
    std::printf("scenario               %s\n", sc.path.c_str());
    std::printf("method                 %s%s\n", s.method.c_str(),
                !is_fixed_step(s.method) ? (" (rtol " + std::to_string(s.rtol) + ", atol " + std::to_string(s.atol) + ")").c_str()
                                                : (" (dt " + std::to_string(s.dt) + " s)").c_str());
    std::printf("quaternion             %s\n", r.quaternion_handling.c_str());
    std::printf("status                 %s\n", r.status.c_str());
    std::printf("t reached              %.6g s\n", r.t_reached);
    std::printf("steps                  %ld\n", r.stats.steps);
    std::printf("RHS evaluations        %ld\n", r.stats.rhs_evals);
    std::printf("Jacobian evaluations   %ld\n", r.stats.jac_evals);
    std::printf("error-test failures    %ld\n", r.stats.error_test_failures);
    std::printf("nonlinear iterations   %ld\n", r.stats.nonlinear_iterations);
    std::printf("CPU time               %.4f s\n", r.cpu_seconds);
    std::printf("energy error (final)   %.3e (relative to max(|E0|, peak T); max over the run %.3e)\n",
                r.final_relative_energy_error, r.max_relative_energy_error);
    std::printf("output                 %s\n", out.c_str());
  }
  if (!r.completed) {
    std::fprintf(stderr, "soadyn: error: %s: %s (logged up to t = %g s in %s)\n", sc.path.c_str(), r.status.c_str(),
                 r.t_reached, out.c_str());
    return 3;
  }
  return 0;
}

}  // namespace soadyn::cli
