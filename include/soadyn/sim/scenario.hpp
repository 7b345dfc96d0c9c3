// A scene as a run takes it: the model, its initial state, the simulation settings and the inputs,
// with where each came from (the scenario file, its robot file) so that every run can store them.
// Read from files by io/scenario_file.hpp; built in code as any aggregate.
#pragma once

#include "soadyn/algorithm/inputs.hpp"
#include "soadyn/multibody/model.hpp"
#include "soadyn/sim/settings.hpp"

#include <map>
#include <string>
#include <vector>

namespace soadyn {

struct Scenario {
  std::string path;   // file it came from
  std::string text;   // its full text, stored with every run
  // the robot file its urdf: or model: key names, as read, and that file's path (empty without
  // one; a .urdf or .xml loaded itself is `text`), stored with every run too (h5log.hpp /robot)
  std::string robot_text, robot_path;
  // an MJCF model's (a .xml loaded itself, or the one model: names): every file handed to MuJoCo's
  // compiler, as handed (MjcfModel::files: the main text, its <include>s and assets), stored with
  // every run (h5log.hpp /model_files) so that soadyn view needs no file on disk; empty otherwise
  std::vector<ModelFile> model_files;
  std::string name;
  std::string description;
  Model model;
  VecX q0, v0;        // initial state (neutral and zero where the file is silent)
  SimulationSettings simulation;
  Inputs inputs;
  std::vector<std::string> log_frames;  // log: {frames: [...]}: frames whose poses a run file logs (/frames)
  // every file the scenario was read from: itself, its robot file, the robot's MJCF <include>s and
  // assets, its target tables; no command writes its output onto one (output_file.hpp)
  std::vector<std::string> files;
  // where the file gives a field a run may refuse later, as "file:line:column" by the field's name
  // (simulation.limits, simulation.sensitivities, initial.q.J, limits.J): check_run names it when
  // a setting, however it was given (the file, --method, Python), makes the run refuse
  std::map<std::string, std::string> locations;
  // what reading the file did that a run says before it starts (check_run's warnings, once the run
  // is not refused): the initial state assembled onto the loops
  std::vector<std::string> notes;
};

}  // namespace soadyn
