// The subcommands of the soadyn executable.
#pragma once

#include "soadyn/types.hpp"

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace soadyn::cli {

// "--q -0.5,1" → "--q=-0.5,1" for the list options, so a leading minus is a value, not an option.
std::vector<std::string> join_negative_values(int argc, char** argv);

// {"a", "b"}, " | " → "a | b"
std::string join(const std::vector<std::string>& items, const std::string& separator);

// "a,b,c" → numbers; throws soadyn::Error naming the option and the bad item.
std::vector<double> parse_list(const std::string& option, const std::string& text);

struct InspectOptions {
  std::string model;
  std::string q, qd, tau, gravity;
  bool free_root = false;
  bool json = false;
  std::string method = "on";
};
void add_inspect(CLI::App& app, InspectOptions& o);
int run_inspect(const InspectOptions& o);

struct RunOptions {
  std::string scenario;
  std::string output;
  std::optional<std::string> method;
  std::optional<double> rtol, atol, dt, t_end, output_dt;
  std::string max_output_size = "1G";  // refuse a run whose projected file is larger
  double flush_interval = 0.5;         // s of wall time between flushes
  bool quiet = false;
};
void add_run(CLI::App& app, RunOptions& o);
int run_simulation(const RunOptions& o);

struct ViewOptions {
  std::string run;
  std::string output;
  double fps = 60.0;         // at most this many frames per simulated second
  long max_frames = 20000;   // and at most this many in all
  bool quiet = false;
};
void add_view(CLI::App& app, ViewOptions& o);
int run_view(const ViewOptions& o);
// soadyn sweep …: replaces this process with python3 -m soadyn sweep … (returns only on failure)
void add_sweep(CLI::App& app);
int exec_sweep(int argc, char** argv);

}  // namespace soadyn::cli
