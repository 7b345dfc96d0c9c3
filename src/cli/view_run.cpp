// soadyn view: a run file read back (the library's reader, run_file.hpp), and the model rebuilt
// from the scenario and robot text stored in it.
#include "view.hpp"

#include "soadyn/io/mjcf.hpp"
#include "soadyn/io/run_file.hpp"
#include "soadyn/io/scenario_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

namespace soadyn::cli::view {

RunFile read_run(const std::string& path) {
  const RunContents c = read_run_file(path);  // a regular file, or the reason it is not (input_file.hpp)
  RunFile r;
  r.path = path;
  r.scenario_text = c.scenario_text;
  if (r.scenario_text.empty()) throw Error(path + ": no scenario stored in the file (not a run file from soadyn run?)");
  r.scenario_path = c.scenario_path;
  r.robot_text = c.robot_text, r.robot_path = c.robot_path;
  r.model_files = c.model_files;
  r.version = c.soadyn_version;
  r.method = c.solver.method, r.status = c.solver.status;
  for (const char* name : {"/time", "/q"})
    if (!c.find(name))
      throw Error(path + ": dataset " + std::string(name) + " is missing (a run logged without the state group, --log, or not a run file from soadyn run)");
  r.time = c.values("/time").col(0);
  r.q = c.values("/q");
  for (auto [name, out] : {std::pair{"/energy/kinetic", &r.kinetic}, {"/energy/total", &r.total},
                           {"/energy/work_inputs", &r.work}, {"/energy/impact_loss", &r.impact_loss},
                           {"/energy/work_prescribed", &r.work_prescribed}})
    if (const RunSeries* s = c.find(name)) *out = s->values.col(0);
  if (c.rows() == 0) throw Error(path + ": the run logged no samples");
  for (Eigen::Index k = 1; k < c.rows(); ++k)
    if (!(r.time(k) >= r.time(k - 1))) throw Error(path + ": /time decreases at row " + std::to_string(k));
  r.joint_names = c.joint_names;
  r.v_names = c.v_names;
  for (const std::string& n : c.column_names)
    if (n.rfind("prescribed.", 0) == 0) r.prescribed.push_back(n.substr(11));
  r.events = c.events;
  r.frame_names = c.frame_names;
  return r;
}

void keep_rows(RunFile& run, Eigen::Index rows) {
  run.time.conservativeResize(rows);
  run.q.conservativeResize(rows, Eigen::NoChange);
  for (VecX* s : {&run.kinetic, &run.total, &run.work, &run.impact_loss, &run.work_prescribed})
    if (s->size()) s->conservativeResize(rows);
}

namespace {

// An MJCF model's files, from the run file only: /model_files, or (a file written before the run
// file stored them) the main text alone when it names no file of its own; else refused, since
// soadyn view never opens a model file on disk (which may have changed since the run).
std::vector<ModelFile> stored_mjcf_files(const RunFile& run, const std::string& text) {
  if (!run.model_files.empty()) return run.model_files;
  if (mjcf_names_files(text))
    throw Error("the MJCF <include>s or names asset files, and the run file was written before the run file stored "
                "the MJCF's files; soadyn view reads nothing but the run file");
  return {ModelFile{"soadyn-model.in-memory.xml", text}};
}

}  // namespace

RunModel rebuild_model(const RunFile& run) {
  const std::string label = run.scenario_path.empty() ? run.path + ":scenario" : run.scenario_path;
  RunModel out;
  try {
    const std::string ext = std::filesystem::path(label).extension().string();
    if (ext == ".xml" && is_mjcf_text(run.scenario_text)) {
      // `soadyn run robot.xml`: an MJCF model, compiled from the files the run handed MuJoCo, as
      // stored (/model_files), never from the disk
      out.mjcf_files = stored_mjcf_files(run, run.scenario_text);
      MjcfOptions mo;
      mo.inertia_check = InertiaCheck::Balance;
      out.model = parse_mjcf_files(out.mjcf_files, label, mo).model;
      if (run.q.cols() == out.model.nq + 7) {  // run with --free-root
        mo.free_root = true;
        out.model = parse_mjcf_files(out.mjcf_files, label, mo).model;
      }
      out.name = std::filesystem::path(label).stem().string();
      out.urdf_text = run.scenario_text;  // its geoms are drawn (view_scene.cpp)
      out.urdf_path = label;
    } else if (ext == ".urdf" || ext == ".URDF" || ext == ".xml") {
      // `soadyn run robot.urdf [--free-root]`: the stored text is the URDF, run with the default
      // gravity; a free root shows as the 7 more columns of q its free joint has.  (The view draws
      // poses only: inertias are balanced rather than refused whatever the run was told.)
      const InertiaCheck any = InertiaCheck::Balance;
      out.model = parse_urdf(run.scenario_text, label, false, Vec3(0, 0, -9.81), any);
      if (run.q.cols() == out.model.nq + 7) out.model = parse_urdf(run.scenario_text, label, true, Vec3(0, 0, -9.81), any);
      out.name = std::filesystem::path(label).stem().string();
      out.urdf_text = run.scenario_text;
      out.urdf_path = label;
    } else {
      // only what the run file holds, never a file on disk: the robot file the scenario names as
      // stored (/robot, layout 4 on), and the scenario without its inputs: (their target tables
      // are files the page does not need; the inputs' kinds are read from the text)
      YAML::Node root;
      try {
        root = YAML::Load(run.scenario_text);
      } catch (const YAML::Exception& e) {
        throw Error(std::string("the stored scenario is not YAML (") + e.what() + ")");
      }
      if (!root.IsMap()) throw Error("the stored scenario is not a YAML mapping");
      if ((root["model"] || root["urdf"]) && run.robot_text.empty())
        throw Error("the file holds no robot file (written before layout 4 stored it), and soadyn view reads nothing "
                    "but the run file");
      bool work_inputs = false;
      if (const YAML::Node in = root["inputs"]; in && in.IsMap()) {
        work_inputs = in["torques"] || in["dampers"] || in["controllers"];
        root.remove("inputs");
      }
      YAML::Emitter text;
      text << root;
      const std::optional<std::string> robot =
          run.robot_text.empty() ? std::nullopt : std::optional<std::string>(run.robot_text);
      // an MJCF robot: compiled from the files the run stored (/model_files), never from the disk
      if (robot && is_mjcf_text(*robot)) out.mjcf_files = stored_mjcf_files(run, *robot);
      const Scenario sc = parse_scenario(root.size() ? std::string(text.c_str()) : std::string("{}"), label, false,
                                         InertiaCheck::Balance, robot, out.mjcf_files.empty() ? nullptr : &out.mjcf_files);
      out.model = sc.model;
      out.name = sc.name;
      out.description = sc.description;
      out.has_work_inputs = work_inputs || !sc.inputs.dampers.empty();
      out.urdf_text = sc.robot_text;
      out.urdf_path = sc.robot_path;
    }
  } catch (const Error& e) {
    throw Error(run.path + ": cannot rebuild the run's model from the scenario stored in it (" + e.what() + ")");
  }
  const Model& m = out.model;
  if (run.q.cols() != m.nq)
    throw Error(run.path + ": /q has " + std::to_string(run.q.cols()) + " columns but the scenario's model has nq = " +
                std::to_string(m.nq) + " (did " + label + " or its URDF change since the run?)");
  if (!run.joint_names.empty() && run.joint_names != m.joint_names)
    throw Error(run.path + ": the joints logged in /model/joint_names differ from the rebuilt model's (did " + label +
                " or its URDF change since the run?)");
  for (const std::string& f : run.frame_names)
    if (m.frame_index(f) < 0)
      throw Error(run.path + ": /frames/names has '" + f + "', a frame the rebuilt model does not have (did " + label +
                  " or its URDF change since the run?)");
  return out;
}

}  // namespace soadyn::cli::view
