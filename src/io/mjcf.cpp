// MJCF import through MuJoCo's own compiler (mj_loadXML), so that <default> classes, <include>,
// childclass, inferred inertias and every frame convention follow MuJoCo exactly; soadyn then reads
// the compiled tree from mjModel's body_*, jnt_* and dof_* arrays.
//
// Frames.  MuJoCo places body b at (body_pos, body_quat) in its parent's frame and moves it by its
// joints in order, each about its anchor jnt_pos along jnt_axis (body axes), the later ones turned
// by the earlier.  A soadyn body's frame has its origin at its joint point, so body b with joints
// j1..jk becomes k specs: the frames F_m = (b's frame turned by j1..j(m−1)) shifted to jnt_pos of
// jm, each placed in the one before by the shift between anchors, the first in its parent's last
// frame; the mass properties go on F_k, the others are massless.  A body without joints is a fixed
// spec (merged into its parent, its name kept as a frame).  A hinge or slide's q is MuJoCo's
// qpos − qpos0 (zero at the pose the file draws); a ball's quaternion is MuJoCo's, relative to that
// pose; a free joint's q is MuJoCo's qpos (body origin and attitude in the world).
#include "soadyn/io/mjcf.hpp"

#include "soadyn/multibody/text.hpp"

#include "mjcf_equality.hpp"
#include "mjcf_values.hpp"
#include "mjcf_vfs.hpp"

#include <mujoco/mujoco.h>

#include <array>
#include <cstring>
#include <memory>
#include <regex>
#include <set>
#include <string>

namespace soadyn {

namespace {

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
using MjModelPtr = std::unique_ptr<mjModel, ModelDeleter>;

struct VfsDeleter {
  void operator()(mjVFS* v) const {
    mj_deleteVFS(v);
    delete v;
  }
};

Mat3 rotation(const mjtNum* quat) {  // MuJoCo's (w, x, y, z)
  return Eigen::Quaterniond(quat[0], quat[1], quat[2], quat[3]).normalized().toRotationMatrix();
}
Vec3 vec3(const mjtNum* x) { return Vec3(x[0], x[1], x[2]); }

std::string name_of(const mjModel* m, int type, int id, const char* kind) {
  const char* n = mj_id2name(m, type, id);
  return n && *n ? std::string(n) : std::string(kind) + std::to_string(id);
}

// Every name soadyn gives: the file's own first (bodies and sites share the frames' names, joints
// have theirs), then the generated ones: an unnamed body "body<id>", an unnamed joint
// "joint<id>", a root's free joint "<body>_free", the frame of each joint of a body but its last
// "<body>.<joint>".  A generated name the file (or an earlier generated one) already has becomes
// "<name>~2" (~3, …: the first free one), and a warning says so, so that no name means two things.
struct Names {
  std::vector<std::string> body, joint, frame, free;  // frame[j]: joint j's frame; free[b]: b's free joint
  std::vector<std::string> renamed;
};

Names unique_names(const mjModel* m, bool free_root) {
  Names n;
  std::set<std::string> frames, joints;
  auto own = [&](int type, int id) {
    const char* s = mj_id2name(m, type, id);
    return s && *s ? std::string(s) : std::string();
  };
  for (int b = 0; b < m->nbody; ++b) frames.insert(own(mjOBJ_BODY, b));
  for (int s = 0; s < m->nsite; ++s) frames.insert(own(mjOBJ_SITE, s));
  for (int j = 0; j < m->njnt; ++j) joints.insert(own(mjOBJ_JOINT, j));
  auto fresh = [&](std::set<std::string>& taken, const std::string& base) {
    std::string name = base;
    for (int k = 2; !taken.insert(name).second; ++k) name = base + "~" + std::to_string(k);
    if (name != base) n.renamed.push_back(printable(base) + " -> " + printable(name));
    return name;
  };
  n.body.resize(size_t(m->nbody));
  n.free.resize(size_t(m->nbody));
  for (int b = 0; b < m->nbody; ++b) {
    n.body[size_t(b)] = own(mjOBJ_BODY, b);
    if (n.body[size_t(b)].empty()) n.body[size_t(b)] = fresh(frames, "body" + std::to_string(b));
  }
  n.joint.resize(size_t(m->njnt));
  for (int j = 0; j < m->njnt; ++j) {
    n.joint[size_t(j)] = own(mjOBJ_JOINT, j);
    if (n.joint[size_t(j)].empty()) n.joint[size_t(j)] = fresh(joints, "joint" + std::to_string(j));
  }
  n.frame.resize(size_t(m->njnt));
  for (int b = 1; b < m->nbody; ++b) {
    for (int k = 0; k + 1 < m->body_jntnum[b]; ++k) {
      const int j = m->body_jntadr[b] + k;
      n.frame[size_t(j)] = fresh(frames, n.body[size_t(b)] + "." + n.joint[size_t(j)]);
    }
    if (free_root && m->body_jntnum[b] == 0 && m->body_parentid[b] == 0) n.free[size_t(b)] = fresh(joints, n.body[size_t(b)] + "_free");
  }
  return n;
}

// "Error: ... \nElement 'joint', line 7" → "path:7: joint: ..."
[[noreturn]] void compile_error(const std::string& path, const std::string& message) {
  std::string what = message;
  for (const char* prefix : {"XML Error: ", "Error: "})
    if (what.rfind(prefix, 0) == 0) what = what.substr(std::strlen(prefix));
  std::smatch where;
  static const std::regex element(R"(\s*Element '([^']*)', line (\d+)\s*)");
  std::string line, elem;
  if (std::regex_search(what, where, element)) {
    elem = where[1];
    line = where[2];
    what = std::string(where.prefix()) + std::string(where.suffix());
  } else {
    static const std::regex xml_line(R"(line (\d+))");
    if (std::regex_search(what, where, xml_line)) line = where[1];
  }
  while (!what.empty() && (what.back() == '\n' || what.back() == ' ')) what.pop_back();
  for (char& c : what)
    if (c == '\n') c = ' ';
  throw Error(path + (line.empty() ? "" : ":" + line) + ": " + (elem.empty() ? "" : elem + ": ") + printable(what));
}

// `stored`: a run's files, compiled from those alone (load_stored_mjcf_files); `handed`: the files
// given to MuJoCo
MjModelPtr compile(const std::string& xml, const std::string& path, bool from_disk, const std::vector<ModelFile>* stored,
                   std::vector<ModelFile>& handed) {
  std::array<char, 1000> error{};
  // the text and the files it names (from the model's folder; the working folder for a run
  // file's stored text), each checked and read by us, handed to MuJoCo in its virtual file
  // system: it never opens a FIFO or a device (mjcf_vfs.hpp)
  std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  std::string name;
  if (stored) {
    name = load_stored_mjcf_files(vfs.get(), *stored, path);
    handed = *stored;
  } else {
    name = mjcf_main_name(from_disk ? mjcf_file_dir(path) : "");
    handed = load_mjcf_files(vfs.get(), name, xml, from_disk ? mjcf_file_dir(path) : "");
  }
  mjModel* m = mj_loadXML(name.c_str(), vfs.get(), error.data(), int(error.size()));
  if (!m) compile_error(path, error.data());
  return MjModelPtr(m);
}

// What soadyn does not model, one line per kind, never silently (`equalities`: the equality
// constraints not held as loops, and the softness of those held)
std::string ignored(const mjModel* m, const std::vector<std::string>& equalities) {
  std::vector<std::string> kinds;
  auto count = [&](int n, const char* one, const char* many) {
    if (n > 0) kinds.push_back(std::to_string(n) + " " + (n == 1 ? one : many));
  };
  int colliding = 0, armature = 0, cones = 0;
  for (int j = 0; j < m->njnt; ++j) cones += m->jnt_limited[j] && m->jnt_type[j] == mjJNT_BALL ? 1 : 0;
  for (int g = 0; g < m->ngeom; ++g) colliding += (m->geom_contype[g] || m->geom_conaffinity[g]) ? 1 : 0;
  for (int k = 0; k < m->nv; ++k) armature += m->dof_armature[k] != 0.0 ? 1 : 0;
  count(colliding, "colliding geom (contacts)", "colliding geoms (contacts)");
  count(m->npair, "contact pair", "contact pairs");
  count(m->ntendon, "tendon", "tendons");
  kinds.insert(kinds.end(), equalities.begin(), equalities.end());
  count(m->nu, "actuator", "actuators");
  count(cones, "ball-joint range (a cone)", "ball-joint ranges (cones)");
  count(armature, "DOF armature (rotor inertia, not in 𝓜)", "DOF armatures (rotor inertia, not in 𝓜)");
  count(m->nsensor, "sensor", "sensors");
  for (std::string& k : mjcf_detail::unmodelled_values(m)) kinds.push_back(std::move(k));
  std::string out;
  for (const std::string& k : kinds) out += (out.empty() ? "" : ", ") + k;
  return out;
}

// MuJoCo's compiler on the text (compile), its warnings kept as notes; a NaN it warns of is an error
MjModelPtr compile_noting(const std::string& xml, const std::string& path, bool from_disk,
                          const std::vector<ModelFile>* stored, std::vector<ModelFile>& handed,
                          std::vector<std::string>& notes) {
  // MuJoCo's warnings and errors come to us: nothing on stdout, nothing in ./MUJOCO_LOG.TXT
  const mjcf_detail::MujocoMessages messages;
  MjModelPtr mp;
  try {
    mp = compile(xml, path, from_disk, stored, handed);
  } catch (const mjcf_detail::MujocoError& e) {
    throw Error(path + ": MJCF: MuJoCo: " + excerpt(e.message, 300));
  }
  for (const std::string& w : messages.warnings()) {
    if (w.find("NaN") != std::string::npos)
      throw Error(path + ": MJCF: MuJoCo: " + excerpt(w, 300) + " (a NaN in the file or an <include>)");
    notes.push_back("MuJoCo: " + excerpt(w, 300));
  }
  return mp;
}

// The specs of MuJoCo's bodies (Frames, above), in order, and where each body's last spec is.
struct Tree {
  std::vector<BodySpec> specs;
  std::vector<int> last_spec;               // each MuJoCo body's last spec (-1: the world)
  std::vector<Vec3> anchor;                 // its last spec's origin in its frame
  std::vector<std::pair<int, int>> coords;  // (MuJoCo joint, soadyn spec) of each joint, in order
};

// spec s's joint kind from MuJoCo joint j's type (nj joints on a body whose parent is `parent`),
// and a hinge's or slide's range in soadyn's q
void set_joint(BodySpec& s, const mjModel* m, int j, int parent, int nj, const std::string& path) {
  const std::string& jname = s.joint_name;
  switch (m->jnt_type[j]) {
    case mjJNT_HINGE: s.joint = JointType::Revolute; break;
    case mjJNT_SLIDE: s.joint = JointType::Prismatic; break;
    case mjJNT_BALL: s.joint = JointType::Ball; break;
    case mjJNT_FREE:
      if (parent != 0 || nj != 1)
        throw Error(path + ": joint '" + printable(jname) +
                    "': a free joint only on a body of the worldbody, and as its only joint");
      s.joint = JointType::Free;
      s.parent = -1;
      s.placement = Placement{};
      break;
    default: throw Error(path + ": joint '" + printable(jname) + "': unknown MuJoCo joint type");
  }
  if (m->jnt_limited[j] && (m->jnt_type[j] == mjJNT_HINGE || m->jnt_type[j] == mjJNT_SLIDE)) {
    // the range, in soadyn's q (qpos − qpos0): the joint's limits (enforced with limits: true)
    const double q0 = m->qpos0[m->jnt_qposadr[j]];
    s.lower = m->jnt_range[2 * j] - q0;
    s.upper = m->jnt_range[2 * j + 1] - q0;
  }
}

// MuJoCo body b's specs: a fixed (or, freed, a free) one without joints, else one per joint F_1..F_k
void add_body(Tree& t, const mjModel* m, int b, const Names& names, const MjcfOptions& o, const std::string& path) {
  std::vector<BodySpec>& specs = t.specs;
  const int parent = m->body_parentid[b];
  const std::string& name = names.body[size_t(b)];
  // b's frame in the parent's last spec frame
  Placement X{rotation(m->body_quat + 4 * b), vec3(m->body_pos + 3 * b) - t.anchor[size_t(parent)]};
  const int nj = m->body_jntnum[b];
  Vec3 at = Vec3::Zero();  // the current spec's origin in b's frame
  auto spec = [&](const std::string& spec_name) -> BodySpec& {
    specs.emplace_back();
    specs.back().name = spec_name;
    return specs.back();
  };
  if (nj == 0) {
    const bool free = o.free_root && parent == 0;
    BodySpec& s = spec(name);
    s.parent = t.last_spec[size_t(parent)];
    s.joint = free ? JointType::Free : JointType::Fixed;
    s.joint_name = free ? names.free[size_t(b)] : name;
    s.placement = free ? Placement{} : X;  // a free joint's q is the pose: the file's goes into q0
  }
  for (int k = 0; k < nj; ++k) {
    const int j = m->body_jntadr[b] + k;
    const Vec3 pos = m->jnt_type[j] == mjJNT_FREE ? Vec3::Zero() : vec3(m->jnt_pos + 3 * j);
    BodySpec& s = spec(k + 1 == nj ? name : names.frame[size_t(j)]);
    s.joint_name = names.joint[size_t(j)];
    s.parent = k == 0 ? t.last_spec[size_t(parent)] : int(specs.size()) - 2;
    s.placement = k == 0 ? Placement{X.R, X.p + X.R * pos} : Placement{Mat3::Identity(), pos - at};
    s.axis = vec3(m->jnt_axis + 3 * j);
    set_joint(s, m, j, parent, nj, path);
    t.coords.emplace_back(j, int(specs.size()) - 1);
    at = pos;
  }
  // mass properties on the last spec: the centre of mass and principal axes (body_ipos,
  // body_iquat) in b's frame, shifted to the spec's origin
  BodySpec& s = specs.back();
  const Mat3 Ri = rotation(m->body_iquat + 4 * b);
  s.mass = m->body_mass[b];
  s.com = vec3(m->body_ipos + 3 * b) - at;
  s.inertia = Ri * vec3(m->body_inertia + 3 * b).asDiagonal() * Ri.transpose();
  t.last_spec[size_t(b)] = int(specs.size()) - 1;
  t.anchor[size_t(b)] = at;
}

// every body's specs, parents before children (MuJoCo's body order)
Tree body_specs(const mjModel* m, const Names& names, const MjcfOptions& o, const std::string& path) {
  Tree t;
  t.last_spec.assign(size_t(m->nbody), -1);
  t.anchor.assign(size_t(m->nbody), Vec3::Zero());
  for (int b = 1; b < m->nbody; ++b) add_body(t, m, b, names, o, path);
  if (t.specs.empty()) throw Error(path + ": MJCF: the worldbody has no bodies");
  return t;
}

// X given in MuJoCo body b's frame, as (model body, placement in its frame; −1: the world): b's
// last spec sits at its anchor, and that spec is a frame of the body it moves with
struct InModel {
  const Model& model;
  const Names& names;
  const std::vector<Vec3>& anchor;
  Placement operator()(int b, Placement X, int& body) const {
    body = -1;
    if (b == 0) return X;
    const int f = model.frame_index(names.body[size_t(b)]);
    X.p -= anchor[size_t(b)];
    body = model.frame_body[size_t(f)];
    return compose(model.frame_placement[size_t(f)], X);
  }
};

// sites as frames; one whose name a body or welded body already has is said, not dropped silently
void add_sites(Model& model, const mjModel* m, const InModel& in_model) {
  std::string taken;
  for (int i = 0; i < m->nsite; ++i) {
    const std::string site = name_of(m, mjOBJ_SITE, i, "site");
    if (model.frame_index(site) >= 0) {
      taken += (taken.empty() ? "" : ", ") + printable(site);
      continue;
    }
    int body = -1;
    const Placement X = in_model(m->site_bodyid[i], {rotation(m->site_quat + 4 * i), vec3(m->site_pos + 3 * i)}, body);
    model.add_frame(site, body, X);
  }
  if (!taken.empty()) model.warnings.push_back("sites not kept as frames (a body has the name): " + taken);
}

// geoms, placed as sites are; the colour by MuJoCo's rule: the geom's rgba unless it is the
// default and the geom has a material
std::vector<MjcfGeom> geoms(const mjModel* m, const InModel& in_model) {
  std::vector<MjcfGeom> out;
  static const char* const kinds[] = {"plane", "hfield", "sphere", "capsule", "ellipsoid", "cylinder", "box", "mesh"};
  for (int g = 0; g < m->ngeom; ++g) {
    const int type = m->geom_type[g];
    if (type < 0 || type > mjGEOM_MESH) continue;
    MjcfGeom geom;
    geom.kind = kinds[type];
    geom.size = vec3(m->geom_size + 3 * g);
    const float* rgba = m->geom_rgba + 4 * g;
    const bool default_rgba = rgba[0] == 0.5f && rgba[1] == 0.5f && rgba[2] == 0.5f && rgba[3] == 1.0f;
    if (default_rgba && m->geom_matid[g] >= 0 && m->geom_matid[g] < m->nmat) rgba = m->mat_rgba + 4 * m->geom_matid[g];
    geom.rgb = Vec3(rgba[0], rgba[1], rgba[2]);
    if (type == mjGEOM_MESH && m->geom_dataid[g] >= 0 && m->geom_dataid[g] < m->nmesh) geom.mesh = m->geom_dataid[g];
    geom.X = in_model(m->geom_bodyid[g], {rotation(m->geom_quat + 4 * g), vec3(m->geom_pos + 3 * g)}, geom.body);
    out.push_back(geom);
  }
  return out;
}

// the meshes as compiled: vertices and triangles in the frame of the geoms that use them
std::vector<MjcfMesh> meshes(const mjModel* m) {
  std::vector<MjcfMesh> out;
  for (int k = 0; k < m->nmesh; ++k) {
    MjcfMesh mesh;
    mesh.name = name_of(m, mjOBJ_MESH, k, "mesh");
    const float* v = m->mesh_vert + 3 * size_t(m->mesh_vertadr[k]);
    mesh.vertices.assign(v, v + 3 * size_t(m->mesh_vertnum[k]));
    const int* f = m->mesh_face + 3 * size_t(m->mesh_faceadr[k]);
    mesh.faces.assign(f, f + 3 * size_t(m->mesh_facenum[k]));
    out.push_back(std::move(mesh));
  }
  return out;
}

// the pose the file draws (q = 0 for hinges and slides), the free joints' poses, the dampers
// and springs the file gives its 1-DOF joints (`passive`: unless <flag passive="disable"/>)
void initial_state(MjcfModel& out, const mjModel* m, const Tree& t, const Names& names, const MjcfOptions& o,
                   bool passive) {
  const Model& model = out.model;
  out.q0 = model.neutral_configuration();
  for (const auto& [j, spec_index] : t.coords) {
    const int body = model.joint_index(t.specs[size_t(spec_index)].joint_name);
    if (body < 0) continue;
    const int iq = model.idx_q[size_t(body)], iv = model.idx_v[size_t(body)];
    const int type = m->jnt_type[j];
    const mjtNum* qpos0 = m->qpos0 + m->jnt_qposadr[j];
    if (type == mjJNT_FREE)
      for (int k = 0; k < 7; ++k) out.q0(iq + k) = qpos0[k];
    if (type == mjJNT_BALL)
      for (int k = 0; k < 4; ++k) out.q0(iq + k) = qpos0[k];
    if (type == mjJNT_HINGE || type == mjJNT_SLIDE) {
      out.qpos0.emplace_back(iq, qpos0[0]);
      const int dof = m->jnt_dofadr[j];
      if (passive && m->dof_damping[dof] > 0.0)
        out.dampers.push_back({model.joint_names[size_t(body)], iv, m->dof_damping[dof]});
      if (passive && m->jnt_stiffness[j] > 0.0)
        out.springs.push_back({model.joint_names[size_t(body)], iv, iq, m->jnt_stiffness[j],
                               m->qpos_spring[m->jnt_qposadr[j]] - qpos0[0]});
    }
  }
  // a body freed by free_root starts where the file draws it
  for (int b = 1; b < m->nbody; ++b)
    if (o.free_root && m->body_parentid[b] == 0 && m->body_jntnum[b] == 0) {
      const int body = model.body_index(names.body[size_t(b)]);
      if (body < 0) continue;
      const int iq = model.idx_q[size_t(body)];
      out.q0.segment<3>(iq) = vec3(m->body_pos + 3 * b);
      for (int k = 0; k < 4; ++k) out.q0(iq + 3 + k) = m->body_quat[4 * b + k];
    }
  model.normalize(out.q0);
}

}  // namespace

static MjcfModel parse_mjcf_impl(const std::string& xml, const std::string& path, bool from_disk,
                          const std::vector<ModelFile>* stored, const MjcfOptions& o);

bool mjcf_available() { return true; }

bool mjcf_names_files(const std::string& xml) { return mjcf_text_names_files(xml); }

MjcfModel parse_mjcf(const std::string& xml, const std::string& path, bool from_disk, const MjcfOptions& o) {
  return parse_mjcf_impl(xml, path, from_disk, nullptr, o);
}

MjcfModel parse_mjcf_files(const std::vector<ModelFile>& files, const std::string& path, const MjcfOptions& o) {
  if (files.empty()) throw Error(path + ": MJCF: the run file holds no model text");
  return parse_mjcf_impl(files[0].data, path, false, &files, o);
}

static MjcfModel parse_mjcf_impl(const std::string& xml, const std::string& path, bool from_disk,
                          const std::vector<ModelFile>* stored, const MjcfOptions& o) {
  // NaN, infinities, negative damping: located (a run's stored files: the main text's, the
  // <include>s' are in the compiled values checked below)
  mjcf_detail::check_file_values(xml, path, from_disk);
  std::vector<std::string> notes;
  std::vector<ModelFile> handed;
  const MjModelPtr mp = compile_noting(xml, path, from_disk, stored, handed, notes);
  const mjModel* m = mp.get();
  mjcf_detail::check_compiled_values(m, path);
  const Names names = unique_names(m, o.free_root);
  const Tree tree = body_specs(m, names, o, path);
  const std::vector<BodySpec>& specs = tree.specs;

  // <flag gravity="disable"/>: no gravity, as MuJoCo runs it
  const Vec3 gravity = o.gravity.value_or((m->opt.disableflags & mjDSBL_GRAVITY) ? Vec3::Zero() : vec3(m->opt.gravity));
  const bool passive = !(m->opt.disableflags & mjDSBL_PASSIVE);  // <flag passive="disable"/>: no dampers, no springs
  MjcfModel out;
  out.files = std::move(handed);
  try {
    out.model = Model::build(specs, gravity, o.inertia_check);
  } catch (const ModelError& e) {
    throw Error(path + ": body '" + printable(specs.at(size_t(e.spec)).name) + "': " + e.detail);
  }
  Model& model = out.model;
  const InModel in_model{model, names, tree.anchor};
  // connect and weld as loops on the model's bodies
  mjcf_detail::EqualityLoops equalities = mjcf_detail::equality_loops(m, [&](int b, const Placement& X, int& body) {
    return in_model(b, X, body);
  });
  out.loops = std::move(equalities.loops);
  if (const std::string what = ignored(m, equalities.ignored); !what.empty()) model.warnings.push_back("ignored: " + what);
  for (const std::string& note : notes) model.warnings.push_back(note);
  if (!names.renamed.empty()) {
    std::string list;
    for (const std::string& r : names.renamed) list += (list.empty() ? "" : ", ") + r;
    model.warnings.push_back("generated names renamed (the file already has the name): " + list);
  }
  add_sites(model, m, in_model);
  out.geoms = geoms(m, in_model);
  out.meshes = meshes(m);
  initial_state(out, m, tree, names, o, passive);
  return out;
}

}  // namespace soadyn
