// soadyn: the command-line front end.
//   soadyn inspect MODEL ...   𝓜(q), bias, q̈, energy and momentum at one state
//   soadyn run MODEL ...       simulate, log to HDF5
//   soadyn view RUN.h5 ...     one self-contained web page that plays the run in 3D
//   soadyn export RUN.h5 ...   the run's samples as CSV or JSON, with names and units
//   soadyn identify SCENE ...  inertial parameters fitted to a run's motion
//   soadyn help [COMMAND]      what a command takes
//   soadyn sweep SWEEP ...     an ensemble of runs on Dask (python3 -m soadyn sweep)
#include "cli.hpp"

#include "soadyn/multibody/text.hpp"
#include "soadyn/io/version.hpp"

#include <CLI/CLI.hpp>

#include <iostream>
#include <string>

int main(int argc, char** argv) {
  if (argc >= 2 && std::string(argv[1]) == "sweep") return soadyn::cli::exec_sweep(argc, argv);
  std::vector<std::string> args = soadyn::cli::join_negative_values(argc, argv);
  CLI::App app{"soadyn: dynamics of tree-structured rigid multibody systems (the note's O(N) operators)", "soadyn"};
  app.require_subcommand(1);
  app.set_version_flag("--version", [] {
    std::string text = "soadyn " + soadyn::version() + "\nbuilt with";
    for (const auto& [name, v] : soadyn::dependency_versions()) text += " " + name + " " + v + ",";
    text.back() = '\n';
    return text + "CLI11 " CLI11_VERSION;
  });
  std::string help_topic;
  CLI::App* help = app.add_subcommand("help", "what soadyn or one of its commands takes (soadyn help run)");
  help->add_option("COMMAND", help_topic, "a command");
  soadyn::cli::InspectOptions inspect;
  soadyn::cli::add_inspect(app, inspect);
  soadyn::cli::RunOptions run;
  soadyn::cli::add_run(app, run);
  soadyn::cli::ViewOptions view;
  soadyn::cli::add_view(app, view);
  soadyn::cli::ExportOptions export_options;
  soadyn::cli::add_export(app, export_options);
  soadyn::cli::IdentifyCommand identify;
  soadyn::cli::add_identify(app, identify);
  soadyn::cli::add_sweep(app);
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend() - 1);
    app.parse(reversed);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::string hint = soadyn::cli::option_suggestion(app, {args.begin() + 1, args.end()});
    std::cerr << "soadyn: error: " << (hint.empty() ? std::string(e.what()) : hint) << " (see soadyn --help)\n";
    return 2;
  }
  try {
    if (app.got_subcommand("help")) {
      if (help_topic.empty()) {
        std::cout << app.get_formatter()->make_help(&app, app.get_name(), CLI::AppFormatMode::Normal);
        return 0;
      }
      for (CLI::App* sub : app.get_subcommands({}))
        if (sub->get_name() == help_topic) {
          std::cout << sub->help(app.get_name());
          return 0;
        }
      std::cerr << "soadyn: error: help: no command '" << help_topic << "' (see soadyn --help)\n";
      return 2;
    }
    if (app.got_subcommand("inspect")) return soadyn::cli::run_inspect(inspect);
    if (app.got_subcommand("run")) return soadyn::cli::run_simulation(run);
    if (app.got_subcommand("view")) return soadyn::cli::run_view(view);
    if (app.got_subcommand("export")) return soadyn::cli::run_export(export_options);
    if (app.got_subcommand("identify")) return soadyn::cli::run_identify(identify);
  } catch (const soadyn::Error& e) {
    // one line of text, whatever a message quotes (every echo site cuts its values already)
    std::cerr << "soadyn: error: " << soadyn::excerpt(e.what(), 4000) << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "soadyn: error: " << soadyn::excerpt(e.what(), 4000) << "\n";
    return 2;
  }
  return 0;
}
