#include "cli.hpp"

#include "soadyn/io/h5log.hpp"
#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/simulate.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>

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

// "512", "800K", "2G", "1.5T" (powers of 1024) → bytes; negative when not a size
double parse_size(const std::string& text) {
  char* end = nullptr;
  double x = std::strtod(text.c_str(), &end);
  if (text.empty() || end == text.c_str() || !(x >= 0) || !std::isfinite(x)) return -1;
  const std::string unit(end);
  const char* units[] = {"", "K", "M", "G", "T", "P"};
  for (int k = 0; k < 6; ++k, x *= 1024)
    if (unit == units[k] || (k > 0 && (unit == std::string(units[k]) + "B" || unit == std::string(units[k]) + "iB"))) return x;
  return -1;
}

const CLI::Validator kSize(
    [](std::string& text) {
      return parse_size(text) < 0 ? "expected a size such as 800M or 2G, got '" + text + "'" : std::string();
    },
    "SIZE");

std::string human_size(double bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int k = 0;
  while (bytes >= 1024 && k < 6) bytes /= 1024, ++k;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g %s", bytes, units[k]);
  return buf;
}
}  // namespace

void add_run(CLI::App& app, RunOptions& o) {
  CLI::App* c = app.add_subcommand(
      "run",
      "Simulate a scenario and log states, energy, momentum and body poses to HDF5.\n"
      "MODEL is a scenario (.yaml) or a robot (.urdf: zero initial state, default settings, 0,0,-9.81 gravity).\n"
      "Command-line values override the scenario's 'simulation' section and initial state.\n"
      "Exit status: 0 completed, 2 bad input or output refused (in use, an input, too large), 3 the run\n"
      "failed (the file keeps what was logged), 4 writing the output failed (the file keeps its last\n"
      "flushed rows), 128+N interrupted by signal N (130 SIGINT, 143 SIGTERM, 129 SIGHUP).");
  c->add_option("MODEL", o.scenario, "scenario (.yaml) or robot (.urdf)")->required();
  c->add_option("-o,--output", o.output, "HDF5 output file (default out/<scenario name>.h5)");
  // one option per simulation setting, from the table (settings.hpp): --t-end for t_end
  for (const SettingInfo& info : setting_table()) {
    std::string flag = "--" + std::string(info.name);
    std::replace(flag.begin(), flag.end(), '_', '-');
    std::string help(info.help);
    if (!info.unit.empty() && info.unit != "1") help += ", " + std::string(info.unit);
    CLI::Option* opt = c->add_option(flag, o.settings[std::string(info.name)], help);
    switch (info.kind) {
      case SettingKind::Word: {
        std::vector<std::string> words = info.words();
        opt->description(help + ": " + join(words, " | "));
        if (!info.old_word.empty()) words.emplace_back(info.old_word);
        opt->transform(one_of(words));
        break;
      }
      case SettingKind::Flag:
        opt->description(help + ": on | off");
        opt->transform(one_of({"on", "off"}));
        break;
      case SettingKind::Real:
      case SettingKind::Count:
        opt->check(CLI::Validator(
            [&info](std::string& text) {
              char* end = nullptr;
              const double x = std::strtod(text.c_str(), &end);
              if (text.empty() || *end != '\0') return "expected a number, got '" + text + "'";
              const std::string p = setting_problem(info, x);
              return p.empty() ? p : p + ", got '" + text + "'";
            },
            "NUMBER"));
        break;
    }
  }
  c->add_option("--max-output-size", o.max_output_size, "refuse a run whose file would be larger (default 1G)")
      ->check(kSize);
  c->add_option("--flush-interval", o.flush_interval, "wall-clock seconds between writes to the file (default 0.5)")
      ->check(kPositive);
  add_state_options(c, o.state, "the initial state");
  c->add_option("--log", o.log,
                "groups of series to log, comma-separated: state (q, qd, qdd), energy, momentum, bodies (poses); "
                "default all; /time is always logged");
  c->add_flag("--force", o.force,
              "replace the output even when it is not a soadyn run file (never an input, a file in use or a device)");
  c->add_flag("-q,--quiet", o.quiet, "no summary on stdout");
}

namespace {

// SIGINT, SIGTERM, SIGHUP: the first ends the run before the next integrator step (simulate's stop hook);
// a second leaves at once, the file as of its last flush (valid: SWMR).  Only async-signal-safe
// calls in the handler.
std::atomic<int> g_stop{0};
char g_tmp_path[4096];   // the file under construction, removed if we leave before it is published
char g_lock_path[4096];  // the lock file

void on_signal(int signo) {
  if (g_stop.load() != 0) {
    if (g_tmp_path[0]) unlink(g_tmp_path);
    if (g_lock_path[0]) unlink(g_lock_path);
    static const char msg[] = "soadyn: interrupted twice: exiting at once (the file keeps its last flush)\n";
    if (write(2, msg, sizeof msg - 1) < 0) {
    }
    _exit(128 + signo);
  }
  g_stop.store(signo);
}

void install_signal_handlers(const std::string& tmp, const std::string& lock) {
  std::snprintf(g_tmp_path, sizeof g_tmp_path, "%s", tmp.c_str());
  std::snprintf(g_lock_path, sizeof g_lock_path, "%s", lock.c_str());
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaction(s, &sa, nullptr);
  // past a file-size limit (ulimit -f) a write fails with EFBIG, handled as a full disk is,
  // instead of the signal ending the process with no message and the lock left behind
  signal(SIGXFSZ, SIG_IGN);
}

// a progress bar on stderr when it is a terminal and the run has taken over a second
class Progress : public RunObserver {
 public:
  Progress(RunObserver* next, double t_end) : next_(next), t_end_(t_end), tty_(isatty(2)) {}
  void on_sample(const Sample& s) override {
    if (next_) next_->on_sample(s);
  }
  void on_event(const LimitEvent& e) override {
    if (next_) next_->on_event(e);
  }
  void on_progress(const RunSummary& r) override {
    if (next_) next_->on_progress(r);
    const auto now = std::chrono::steady_clock::now();
    if (!tty_ || now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const int width = 40, done = int(width * std::min(1.0, r.t_reached / t_end_));
    std::fprintf(stderr, "\r[%.*s%*s] t = %.4g / %.4g s", done, "########################################", width - done, "",
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

void warn(const std::string& what) { std::fprintf(stderr, "soadyn: warning: %s\n", what.c_str()); }

}  // namespace

namespace {

// the settings the command line gives, over the scenario's (checked by the options' validators)
SimulationSettings settings_from_options(const Scenario& sc, const RunOptions& o) {
  SimulationSettings s = sc.simulation;
  for (const auto& [name, text] : o.settings) {  // checked by the options' validators
    if (text.empty()) continue;
    const SettingInfo& info = *find_setting(name);
    switch (info.kind) {
      case SettingKind::Word: set_setting(s, info, text); break;
      case SettingKind::Flag: set_setting(s, info, text == "on"); break;
      default: set_setting(s, info, std::strtod(text.c_str(), nullptr)); break;
    }
  }
  return s;
}

// the run file's projected size, refused beyond --max-output-size: the row as the file will hold it
// (the sensitivities, frames, controls and impacts included) and the MJCF model's files the file
// stores (/model_files)
void check_output_size(const Scenario& sc, const SimulationSettings& s, const LogGroups& groups, const RunOptions& o,
                       const std::string& out) {
  const std::uint64_t row = row_bytes(sc.model, logged_groups(sc, s, groups));
  std::uint64_t stored = 0;
  for (const ModelFile& f : sc.model_files) stored += f.data.size();
  const double rows = output_rows(s), bytes = rows * double(row) + double(stored), limit = parse_size(o.max_output_size);
  if (bytes > limit) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "%.6g rows of %llu bytes", rows, static_cast<unsigned long long>(row));
    if (stored > 0)
      std::snprintf(buf + std::strlen(buf), sizeof buf - std::strlen(buf), " and %llu bytes of the MJCF model's files",
                    static_cast<unsigned long long>(stored));
    throw Error(out + ": the output would take " + human_size(bytes) + " (" + buf + "), more than --max-output-size " +
                o.max_output_size + ": raise --output-dt, lower --t-end, or allow it with --max-output-size");
  }
}

// the summary on stdout: the method, the solver's statistics, the energy balance, events, output
void print_summary(const Scenario& sc, const SimulationSettings& s, const RunSummary& r, const H5Log& log,
                   const std::string& out) {
  const std::string method(to_string(s.method));
  std::printf("scenario               %s\n", sc.path.c_str());
  const std::string newton(to_string(s.newton));
  // with closed loops the multipliers are not differentiated: ∂f/∂y by differences (system.hpp)
  const std::string jacobian = sc.inputs.loops.empty() ? std::string(to_string(s.jacobian)) : "difference";
  if (s.method == Method::ImplicitMidpoint)
    std::printf("method                 %s (dt %g s, %s Newton, %s Jacobian)\n", method.c_str(), s.dt, newton.c_str(),
                jacobian.c_str());
  else if (s.method == Method::Variational)
    std::printf("method                 %s (dt %g s, %s)\n", method.c_str(), s.dt,
                s.newton == Newton::Simplified ? "chord iterations with M, Newton where they stall" : "Newton");
  else if (is_fixed_step(s.method))
    std::printf("method                 %s (dt %g s)\n", method.c_str(), s.dt);
  else if (s.method == Method::CvodeBdf)
    std::printf("method                 %s (rtol %g, atol %g, %s Jacobian)\n", method.c_str(), s.rtol, s.atol,
                jacobian.c_str());
  else
    std::printf("method                 %s (rtol %g, atol %g)\n", method.c_str(), s.rtol, s.atol);
  std::printf("quaternion             %s\n", r.quaternion_handling.c_str());
  std::printf("status                 %s\n", r.status.c_str());
  std::printf("t reached              %.9g s\n", r.t_reached);
  std::printf("steps                  %ld\n", r.stats.steps);
  std::printf("RHS evaluations        %ld\n", r.stats.rhs_evals);
  std::printf("Jacobian evaluations   %ld\n", r.stats.jac_evals);
  std::printf("error-test failures    %ld\n", r.stats.error_test_failures);
  std::printf("nonlinear iterations   %ld\n", r.stats.nonlinear_iterations);
  std::printf("CPU time               %.4g s\n", r.cpu_seconds);
  if (sc.inputs.prescribed.empty())
    std::printf("energy balance error   %.3g (final; max over the run %.3g): |E(t) - E(0) - W(t)| / max(|E0|, peak T, peak |W|),\n"
                "                       W the work of torques and dampers\n",
                r.final_energy_balance_error, r.max_energy_balance_error);
  else
    std::printf("energy balance error   %.3g (final; max over the run %.3g): |E(t) - E(0) - W(t) - W_p(t)| / max(|E0|, "
                "peak T, peak |W|, peak |W_p|),\n                       W the work of torques and dampers, W_p the prescribed joints' torques'\n",
                r.final_energy_balance_error, r.max_energy_balance_error);
  if (!sc.inputs.prescribed.empty()) {
    std::string joints;
    for (const PrescribedInput& p : sc.inputs.prescribed) joints += (joints.empty() ? "" : ", ") + p.joint;
    std::printf("prescribed             %s (their torques in /prescribed)\n", joints.c_str());
  }
  if (!r.events.empty()) {
    // the limits' events (in the run file's /events): how many, the energy the impacts took, the first
    double lost = 0;
    for (const LimitEvent& e : r.events) lost += e.energy_lost;
    const LimitEvent& first = r.events.front();
    std::printf("limit events           %zu (impacts took %.3g J, in the balance; the first at t = %.9g s, %s at its %s limit)\n",
                r.events.size(), lost, first.t, first.joint.c_str(), first.side < 0 ? "lower" : "upper");
  }
  if (log.published())
    std::printf("output                 %s (%ld flushes, %.3g ms each)\n", out.c_str(), log.flushes(),
                1e3 * log.flush_seconds() / double(std::max(1L, log.flushes())));
  else
    std::printf("output                 none (nothing written; an existing %s is unchanged)\n", out.c_str());
  std::fflush(stdout);
}

}  // namespace

int run_simulation(const RunOptions& o) {
  // everything is checked before any file is touched
  const LogGroups groups = LogGroups::parse(o.log);
  Scenario sc = load_with_options(o.scenario, o.state);
  state_from_options(sc.model, o.state, sc.q0, sc.v0);
  const SimulationSettings s = settings_from_options(sc, o);
  const auto given = [&](const char* name) {
    const auto it = o.settings.find(name);
    return it != o.settings.end() && !it->second.empty();
  };
  const std::string out = o.output.empty() ? "out/" + sc.name + ".h5" : o.output;

  // controller ticks, named by the option that set them (the scenario's own are checked as it is read)
  if (given("control_dt") || given("t_end"))
    if (const std::string p = control_ticks_problem(s.t_end, s.control_dt); !p.empty())
      throw Error(std::string(given("control_dt") ? "--control-dt" : "--t-end") + ": " + p);
  for (const auto& w : check_run(sc, s)) warn(w);
  const std::string method(to_string(s.method));
  if (is_fixed_step(s.method) && (given("rtol") || given("atol")))
    warn(std::string(given("rtol") ? "--rtol" : "--atol") + " has no effect with " + method + " (a fixed-step method; see --dt)");
  if (!is_fixed_step(s.method) && given("dt")) warn("--dt has no effect with " + method + " (it chooses its own steps; see --rtol)");
  check_output_size(sc, s, groups, o, out);
  // never onto a file the run reads (the scenario, its robot and includes, its tables), forced or not
  std::vector<std::string> inputs = sc.files;
  inputs.push_back(o.scenario);
  check_output_path(out, OutputKind::Run, inputs, o.force);
  OutputLock lock(out);
  install_signal_handlers(H5Log::temporary_path(out), lock.lock_path());

  std::unique_ptr<H5Log> log;
  RunSummary r;
  try {
    log = std::make_unique<H5Log>(out, sc, s, SOADYN_VERSION, groups);
    log->set_flush_interval(o.flush_interval);
    Progress progress(log.get(), s.t_end);
    r = simulate(sc, s, &progress, nullptr, &g_stop);
    for (const std::string& w : r.warnings) warn(w);
    if (!r.stiffness_hint.empty()) std::fprintf(stderr, "soadyn: hint: %s\n", r.stiffness_hint.c_str());
  } catch (const IoError& e) {
    std::fprintf(stderr, "soadyn: error: %s\n", e.what());
    return 4;
  }

  if (!o.quiet) {
    print_summary(sc, s, r, *log, out);
  }
  const std::string kept = log->published() ? "logged up to there in " + out
                                             : "nothing written; an existing " + out + " is unchanged";
  if (const int signo = g_stop.load(); signo > 0 && !r.completed) {
    std::fprintf(stderr, "soadyn: %s (%s)\n", r.status.c_str(), kept.c_str());
    return 128 + signo;
  }
  if (!r.completed) {
    std::fprintf(stderr, "soadyn: error: %s: %s (%s)\n", sc.path.c_str(), r.status.c_str(), kept.c_str());
    return 3;
  }
  return 0;
}

}  // namespace soadyn::cli
