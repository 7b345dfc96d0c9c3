// MJCF (MuJoCo's model format) import, through MuJoCo's own compiler when soadyn is built with it
// (Debian libmujoco-dev; mjcf_available()).  The tree part of the file becomes a Model: bodies,
// inertias (given or inferred from geoms by MuJoCo), hinge, slide, ball and free joints, several
// joints in one body (a chain of massless frames), sites as frames, the option's gravity, and the
// active <equality connect> and <equality weld> as loops (held exactly: MuJoCo's solref/solimp
// softness is not modelled).  What soadyn does not model (contacts, tendons, joint and tendon
// equalities, actuators, armature, sensors) is listed in one "ignored: …" warning
// (Model::warnings), never silently.
#pragma once

#include "soadyn/algorithm/inputs.hpp"
#include "soadyn/algorithm/loops.hpp"
#include "soadyn/multibody/model.hpp"

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace soadyn {

struct MjcfOptions {
  bool free_root = false;              // a worldbody child without joints gets a free joint
  std::optional<Vec3> gravity;         // default: the file's <option gravity> (MuJoCo: 0 0 −9.81)
  InertiaCheck inertia_check = InertiaCheck::Warn;
};

// A geom, for drawing: in the frame of the model body its MuJoCo body moves with (−1: the world).
struct MjcfGeom {
  int body = -1;
  Placement X;
  std::string kind;          // box | sphere | cylinder | capsule | ellipsoid | mesh | plane | hfield
  Vec3 size = Vec3::Zero();  // MuJoCo's geom_size: half-sizes (box, ellipsoid), radius and half-length
  Vec3 rgb = Vec3::Constant(0.5);  // the geom's rgba, else its material's (MuJoCo's rule: a geom rgba
                                   // other than the default 0.5 0.5 0.5 1 takes precedence)
  int mesh = -1;                   // a mesh geom: its index in MjcfModel::meshes
};

// A mesh as MuJoCo compiled it (scaled, and moved to its centre of mass and principal axes, the
// geoms that use it placed to match): vertices and triangles in the frame of those geoms.
struct MjcfMesh {
  std::string name;
  std::vector<float> vertices;  // x y z per vertex
  std::vector<int> faces;       // three vertex indices per triangle
};

struct MjcfModel {
  Model model;
  VecX q0;                                    // the pose the file draws (free joints: their pose)
  std::vector<std::pair<int, double>> qpos0;  // (q index, MuJoCo's qpos0) of each hinge and slide:
                                              // soadyn q = MuJoCo qpos − qpos0 there
  std::vector<DamperInput> dampers;           // the joints' damping
  std::vector<SpringInput> springs;           // the joints' stiffness about springref
  std::vector<MjcfGeom> geoms;                // every geom, for soadyn view
  std::vector<MjcfMesh> meshes;               // every mesh asset, for soadyn view
  // the active <equality connect> (a point loop: body1's anchor on body2's point where it was at
  // qpos0) and <equality weld> (a weld loop: body1's frame at relpose on body2's at its anchor;
  // torquescale 0, no rotation held: a point loop), named by the equality's name or
  // "equality<id>", on the model bodies their MuJoCo bodies move with.  Closed at q0 but for a
  // weld whose relpose is not the drawn one (a scenario assembles q0 onto them).
  std::vector<LoopConstraint> loops;
  // every file handed to MuJoCo's compiler, as handed (the name given to its virtual file system,
  // the bytes): the main text first, then the <include>s and mesh, skin, height-field and texture
  // files it read.  A run stores them (h5log.hpp /model_files) for parse_mjcf_files.
  std::vector<ModelFile> files;
};

// Whether this build reads MJCF (MuJoCo found at build time).
bool mjcf_available();
// Whether an XML text is MJCF (its first element is <mujoco>), as opposed to URDF's <robot>.
bool is_mjcf_text(const std::string& text);
// Compiles `xml` (read from `path` when from_disk, so <include> and mesh paths resolve beside it;
// else the text alone) and builds the model.  Throws soadyn::Error as "path:line: element: what"
// where MuJoCo's compiler gives a line.
MjcfModel parse_mjcf(const std::string& xml, const std::string& path, bool from_disk, const MjcfOptions& options = {});
// Compiles a model from the files a run stored (MjcfModel::files, the main text first) and nothing
// else: MuJoCo is handed those bytes only, and a file the model names that is not among them is
// refused ("path: MJCF: NAME: not among the model's files the run file holds; …"), never read from
// disk.  `path` names the model in messages.
MjcfModel parse_mjcf_files(const std::vector<ModelFile>& files, const std::string& path, const MjcfOptions& options = {});
// Whether an MJCF text names files of its own (<include>s, mesh, skin, height-field or texture
// files): none of them is read.
bool mjcf_names_files(const std::string& xml);
// A run stores an MJCF file's own text, not the files it <include>s: compiled again from `path`
// when that file still holds the stored text (so its <include>s resolve), else from the text.
bool mjcf_file_unchanged(const std::string& path, const std::string& stored_text);

}  // namespace soadyn
