// soadyn view: the pieces behind the page (see view.cpp for the page itself).
//   view_run.cpp    a run file read back (run_file.hpp), the model rebuilt from the text stored in it
//   view_scene.cpp  what each body looks like: skeleton, centre of mass, inertia box, URDF visuals
//   view_meshes.cpp the visuals' mesh files: found, read, checked, each embedded once
#pragma once

#include "soadyn/io/mjcf.hpp"
#include "soadyn/multibody/model.hpp"
#include "soadyn/io/run_file.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <filesystem>
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
  VecX work_prescribed;                  // T: W_p(t), the prescribed joints' torques' work (empty without them)
  std::vector<std::string> prescribed;   // the joints whose motion was prescribed (/prescribed's columns)
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
  std::string kind;  // box | cylinder | sphere | mesh
  Vec3 size = Vec3::Zero();  // box: edge lengths; cylinder: radius, length (along z), 0; sphere: radius;
                             // mesh: its scale along x, y, z
  Vec3 p = Vec3::Zero();
  Eigen::Quaterniond R = Eigen::Quaterniond::Identity();
  std::string color;  // "#rrggbb" from the URDF material (MJCF: the geom's or its material's), or empty
  int mesh = -1;      // a mesh: its file in Look::meshes
};

// A mesh file of the model's visuals, in the page once however many visuals use it.
struct MeshFile {
  std::string name;    // as the model names it: a URDF <mesh filename>, an MJCF mesh's name
  std::string key;     // what makes two the same: the file's resolved path, the MJCF mesh
  std::string format;  // stl | obj | dae (the file's bytes) | arrays (an MJCF mesh as MuJoCo compiled it)
  std::string bytes;   // the file; arrays: float32 x y z per vertex, then uint32 triangles
  size_t vertices = 0, triangles = 0;  // arrays
  std::string error;   // why it is not drawn (bytes empty): its bodies keep their default shape
};

// A page holds at most this much of mesh files: 64 MiB each, 128 MiB in all (base64 in the page:
// 4/3 of that).  A file past either is not drawn, and the page's note says why.
inline constexpr std::uint64_t kMaxMeshBytes = std::uint64_t(64) << 20;
inline constexpr std::uint64_t kMaxMeshBytesTotal = std::uint64_t(128) << 20;

// The mesh files a URDF's visuals name, read when the page is written (view_meshes.cpp).
class UrdfMeshes {
 public:
  UrdfMeshes(const std::string& urdf_path, std::vector<MeshFile>& files);
  // the index in `files` of the file a <mesh filename> names (package://, file://, absolute, or
  // relative to the URDF), read and checked now; one that cannot be drawn keeps the reason
  int add(const std::string& filename);

 private:
  std::vector<MeshFile>& files_;
  std::filesystem::path dir_;  // the URDF's folder, absolute
  std::uint64_t total_ = 0;
};

// An MJCF mesh as MuJoCo compiled it, for the page
MeshFile compiled_mesh(const MjcfMesh& mesh);

struct BodyLook {
  std::vector<Vec3> segments;  // skeleton: body-frame end points of capsules from the joint (origin)
  Shape inertia_box;           // the uniform box with the body's mass and principal moments
  std::vector<Shape> visuals;  // URDF <visual> and MJCF geom primitives and meshes
  int meshes = 0;              // the meshes among them
};

struct Look {
  std::vector<BodyLook> bodies;
  std::vector<Shape> world_visuals;  // visuals of links welded to the world
  int world_meshes = 0;
  std::vector<MeshFile> meshes;      // the files the mesh visuals name
};

// Skeleton and inertia box from the model; visuals from the URDF text when there is one.
// An MJCF model's geoms are compiled from `mjcf_files` (RunModel::mjcf_files) alone.
Look make_look(const Model& model, const std::string& urdf_text, const std::string& urdf_path,
               const std::vector<ModelFile>& mjcf_files = {});

}  // namespace soadyn::cli::view
