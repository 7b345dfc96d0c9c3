// soadyn view: the pieces behind the page (see view.cpp for the page itself).
//   view_run.cpp    a run file read back (run_file.hpp), the model rebuilt from the text stored in it
//   view_scene.cpp  what each body looks like: skeleton, centre of mass, inertia box, URDF visuals
#pragma once

#include "soadyn/model.hpp"
#include "soadyn/run_file.hpp"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace soadyn::cli::view {

// The parts of a run file the page shows.
struct RunFile {
  std::string path;
  std::string scenario_text, scenario_path, version;
  std::string robot_text, robot_path;    // the robot file the scenario named, as stored (layout 4)
  std::vector<ModelFile> model_files;    // an MJCF model's files as the run handed them to MuJoCo (/model_files)
  std::string method, status;
  std::vector<std::string> joint_names;  // as logged (empty if the file has none)
  VecX time;                             // T
  MatX q;                                // T × nq
  VecX kinetic, total;                   // T (empty if absent)
  VecX work;                             // T: the inputs' work W(t) (empty in files before layout 3)
  std::vector<std::string> frame_names;  // the frames a scenario's log: frames: logged (/frames/names)
  VecX impact_loss;                      // T: L(t), the energy the limits' impacts took (empty without limits)
  std::vector<std::string> v_names;      // /model v_names (empty if the file has none)
  std::vector<RunEvent> events;          // the joint limits' events (/events, run_file.hpp), in time order
};

// Keeps the first `rows` samples of every series (a run stopped mid-write, or one gone non-finite).
void keep_rows(RunFile& run, Eigen::Index rows);

// Reads `path`; throws soadyn::Error naming the file and what is missing or malformed.
RunFile read_run(const std::string& path);

// The model the run was made with, rebuilt from the scenario and robot text stored in the file,
// never the files on disk; a file from before layout 4 (no /robot) reads the robot file its
// scenario names from disk, with a note on stderr.  Throws soadyn::Error if it cannot be (an old
// file's URDF that moved) or does not match the logged q.
struct RunModel {
  Model model;
  std::string name, description;
  std::string urdf_text, urdf_path;  // the URDF the model came from, if any
  std::vector<ModelFile> mjcf_files;  // an MJCF model's files (the main text first), from the run file only
  bool has_work_inputs = false;      // torques or dampers: E is not expected to stay constant
};
RunModel rebuild_model(const RunFile& run);

// One drawn shape, in its body's frame (or the world's).
struct Shape {
  std::string kind;  // box | cylinder | sphere
  Vec3 size = Vec3::Zero();  // box: edge lengths; cylinder: radius, length (along z), 0; sphere: radius
  Vec3 p = Vec3::Zero();
  Eigen::Quaterniond R = Eigen::Quaterniond::Identity();
  std::string color;  // "#rrggbb" from the URDF material, or empty
};

struct BodyLook {
  std::vector<Vec3> segments;  // skeleton: body-frame end points of capsules from the joint (origin)
  Shape inertia_box;           // the uniform box with the body's mass and principal moments
  std::vector<Shape> visuals;  // URDF <visual> primitives
  int meshes = 0;              // URDF <visual> meshes (drawn as the default shape)
};

struct Look {
  std::vector<BodyLook> bodies;
  std::vector<Shape> world_visuals;  // visuals of links welded to the world
  int world_meshes = 0;
};

// Skeleton and inertia box from the model; visuals from the URDF text when there is one.
// An MJCF model's geoms are compiled from `mjcf_files` (RunModel::mjcf_files) alone.
Look make_look(const Model& model, const std::string& urdf_text, const std::string& urdf_path,
               const std::vector<ModelFile>& mjcf_files = {});

}  // namespace soadyn::cli::view
