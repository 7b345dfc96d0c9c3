// The subcommands of the soadyn executable.
#pragma once

#include "soadyn/multibody/model.hpp"
#include "soadyn/io/output_file.hpp"
#include "soadyn/sim/scenario.hpp"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <memory>
#include <map>
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
// a list option of `size` numbers (parse_list), or `fallback` when the text is empty
VecX vector_option(const std::string& option, const std::string& text, int size, const VecX& fallback);

// A choice among `names`, matched ignoring case and stored as spelled there; anything else is
// "expected a | b, got 'x'; did you mean 'a'?"
CLI::Validator one_of(const std::vector<std::string>& names);
// For a command line CLI11 refused: "'--tend' is not an option of soadyn run; did you mean
// '--t-end'?" for the first argument that is not an option of the command it names, with a
// near name; empty when there is none.
std::string option_suggestion(CLI::App& app, const std::vector<std::string>& args);

// The model options every command that takes a model has (inspect and run): --free-root,
// --inertia-check, and --q, --qd, --gravity: a state and a gravity other than the scenario's
struct StateOptions {
  std::string q, qd, gravity;
  bool free_root = false;
  std::string inertia_check;  // warn | balance | strict, empty: the scenario's
};
// adds the five options; `what` says what the state is for ("the state", "the initial state")
void add_state_options(CLI::App* command, StateOptions& o, const std::string& what);
// the scenario or URDF the options say, with the model's warnings (Model::warnings) on stderr
Scenario load_with_options(const std::string& path, const StateOptions& o);
// q (unit quaternions checked, then normalized) and v from --q and --qd, else `q0`, `v0`; throws
// soadyn::Error naming the option, what was expected and what was got
void state_from_options(const Model& model, const StateOptions& o, VecX& q, VecX& v);

// Checks every output of a command before any is touched (check_output_path), and that no two
// name one file; an empty path is skipped.  Returns each one's target.
std::vector<OutputTarget> check_outputs(const std::vector<std::pair<std::string, OutputKind>>& outputs,
                                        const std::vector<std::string>& inputs, bool force);

// A text output of view or export: the path's lock (a regular file), its TextOutput, and
// SIGINT/SIGTERM/SIGHUP handlers that remove both before the process exits with 128+N.
class TextWriter {
 public:
  TextWriter(const std::string& path, OutputTarget target);
  ~TextWriter();
  TextWriter(const TextWriter&) = delete;
  TextWriter& operator=(const TextWriter&) = delete;
  void write(const std::string& text) { out_->write(text); }
  void commit();
  const std::string& path() const { return out_->path(); }

 private:
  std::unique_ptr<OutputLock> lock_;  // declared first: released after the output is gone
  std::unique_ptr<TextOutput> out_;
};

struct InspectOptions {
  std::string model;
  StateOptions state;
  std::string tau;
  bool json = false;
  std::string method = "aba";
  std::vector<std::string> frames;  // --frame: named frames whose pose and Jacobian are printed
};
void add_inspect(CLI::App& app, InspectOptions& o);
int run_inspect(const InspectOptions& o);

struct RunOptions {
  std::string scenario;
  std::string output;
  std::map<std::string, std::string> settings;  // --t-end 2 …: one option per setting of setting_table(), by name
  StateOptions state;
  std::string log = "all";             // the groups logged: state, energy, momentum, bodies
  std::string max_output_size = "1G";  // refuse a run whose projected file is larger
  double flush_interval = 0.5;         // s of wall time between flushes
  bool force = false;                  // replace an output that is not a soadyn run file
  bool quiet = false;
};
void add_run(CLI::App& app, RunOptions& o);
int run_simulation(const RunOptions& o);

struct ViewOptions {
  std::string run;
  std::string output;
  double fps = 60.0;         // at most this many frames per simulated second
  long max_frames = 20000;   // and at most this many in all
  bool force = false;        // replace an output that is not a soadyn page
  bool quiet = false;
};
void add_view(CLI::App& app, ViewOptions& o);
int run_view(const ViewOptions& o);
struct ExportOptions {
  std::string run;
  std::string csv, json;  // outputs ("-": stdout)
  std::string columns;    // comma-separated names, groups or joint/body names (empty: all)
  long every = 1;         // keep every K-th row
  bool list = false;      // print the columns instead
  bool force = false;     // replace outputs that are not soadyn exports
  bool quiet = false;
};
void add_export(CLI::App& app, ExportOptions& o);
int run_export(const ExportOptions& o);

struct IdentifyCommand {
  std::string scenario, data, parameters, output;
  std::string method = "auto";     // auto | least-squares | gauss-newton
  double rank_tolerance = 1e-8;
  int max_iterations = 20;
  double window = 0.1;             // Gauss-Newton: s simulated from each logged state
  bool force = false;              // replace an output that is not a fitted scenario
  bool quiet = false;
};
void add_identify(CLI::App& app, IdentifyCommand& o);
int run_identify(const IdentifyCommand& o);

// soadyn sweep …: replaces this process with python3 -m soadyn sweep … (returns only on failure)
void add_sweep(CLI::App& app);
int exec_sweep(int argc, char** argv);

}  // namespace soadyn::cli
