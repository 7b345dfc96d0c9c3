#include "soadyn/multibody/model.hpp"

#include "model_checks.hpp"

#include "soadyn/multibody/inertia.hpp"
#include "soadyn/multibody/text.hpp"
#include "soadyn/multibody/configuration.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace soadyn {

namespace {

// Where a spec body ends up: the model body it is welded into (-1 = the world) and its frame there.
struct Target {
  int body = -1;
  Placement X;  // spec body frame in the target body frame
};

// mass properties of two bodies about their common centre of mass, in one frame
void merge_mass(double& m, Vec3& c, Mat3& I, double m2, const Vec3& c2, const Mat3& I2) {
  const double mt = m + m2;
  if (mt == 0.0) return;
  const Vec3 ct = (m * c + m2 * c2) / mt;
  I = I + parallel_axis(m, c - ct) + I2 + parallel_axis(m2, c2 - ct);
  m = mt;
  c = ct;
}

}  // namespace

namespace {

// A welded body (a fixed joint): its mass properties merged into the model body it is welded to
// (or the world), and it stays a named frame on that body
void weld(Model& m, const BodySpec& b, const Target& parent_target, const Placement& joint_in_target, Target& target) {
  target = {parent_target.body, joint_in_target};
  const Mat3 Rt = joint_in_target.R;
  const Vec3 c = joint_in_target.p + Rt * b.com;
  const Mat3 I = Rt * b.inertia * Rt.transpose();
  if (parent_target.body < 0) {
    m.world_mass += b.mass;
    m.world_first_moment += b.mass * c;
  } else {
    const int t = parent_target.body;
    merge_mass(m.mass[t], m.com[t], m.inertia[t], b.mass, c, I);
    m.merged_names[t].push_back(b.name);
  }
  // the welded body stays a named frame on the body it went into
  m.frame_names.push_back(b.name);
  m.frame_body.push_back(parent_target.body);
  m.frame_placement.push_back(joint_in_target);
}

// A moving body: model body k = nbodies, its joint's coordinates after those of the bodies before it
void add_body(Model& m, const BodySpec& b, int parent, const Placement& joint_in_target) {
  const int k = m.nbodies++;
  m.frame_names.push_back(b.name);
  m.frame_body.push_back(k);
  m.frame_placement.emplace_back();
  m.parent.push_back(parent);
  m.joint_type.push_back(b.joint);
  m.axis.push_back(joint_traits(b.joint).has_axis ? Vec3(b.axis.normalized()) : Vec3::Zero());
  m.pitch.push_back(b.joint == JointType::Helical ? b.pitch : 0.0);
  m.placement.push_back(joint_in_target);
  m.mass.push_back(b.mass);
  m.com.push_back(b.com);
  m.inertia.push_back(0.5 * (b.inertia + b.inertia.transpose()));
  m.body_names.push_back(b.name);
  m.joint_names.push_back(b.joint_name.empty() ? b.name : b.joint_name);
  m.merged_names.emplace_back();
  m.idx_q.push_back(m.nq);
  m.idx_v.push_back(m.nv);
  m.nq_i.push_back(joint_nq(b.joint));
  m.nv_i.push_back(joint_nv(b.joint));
  // travel: 1-DOF joints only, where the coordinate is the DOF
  const bool travels = joint_nv(b.joint) == 1 && joint_nq(b.joint) == 1;
  for (int j = 0; j < joint_nv(b.joint); ++j) {
    m.lower.push_back(travels ? b.lower : -std::numeric_limits<double>::infinity());
    m.upper.push_back(travels ? b.upper : std::numeric_limits<double>::infinity());
    m.effort.push_back(travels ? b.effort : std::numeric_limits<double>::infinity());
  }
  m.nq += joint_nq(b.joint);
  m.nv += joint_nv(b.joint);
}

// each moving body, with everything welded to it, must be a rigid body with mass; or a massless
// frame that moving bodies hang from (one of several joints in one MJCF body, a bare gimbal ring),
// which the positive definiteness of 𝓜 then decides
void check_bodies(const Model& m, const std::vector<BodySpec>& specs, const std::vector<int>& spec_of) {
  std::vector<char> has_child(size_t(m.nbodies), 0);
  for (int k = 0; k < m.nbodies; ++k)
    if (m.parent[k] >= 0) has_child[size_t(m.parent[k])] = 1;
  for (int k = 0; k < m.nbodies; ++k) {
    BodySpec merged = specs[spec_of[k]];
    merged.inertia = m.inertia[k];
    if (!std::isfinite(m.mass[k]) || !m.inertia[k].allFinite())
      model_checks::refuse(merged, spec_of[k], "mass", "welded bodies whose combined inertia a double can hold",
                           "an overflow (not finite) merging their masses and inertias about the joint frame");
    if (m.mass[k] == 0.0 && has_child[size_t(k)] && m.inertia[k].isZero(0.0)) continue;
    if (!(m.mass[k] > 0.0))
      model_checks::refuse(merged, spec_of[k], "mass",
                           "a positive mass for a moving body" +
                               std::string(m.merged_names[k].empty() ? "" : " (with the bodies welded to it)"),
                           model_checks::fmt(m.mass[k]));
    model_checks::check_inertia(merged, spec_of[k], m.mass[k], m.inertia[k]);
  }
}

// the DOF tree for the LᵀDL factorization, λ(k), and the depth (nilpotency of Φ_D); I_η per body
void dof_tree(Model& m) {
  std::vector<int> level(m.nbodies, 0);
  for (int i = 0; i < m.nbodies; ++i) {
    const int p = m.parent[i];
    level[i] = p < 0 ? 1 : level[p] + 1;
    m.depth = std::max(m.depth, level[i]);
    for (int j = 0; j < m.nv_i[i]; ++j) {
      const int k = m.idx_v[i] + j;
      m.dof_body.push_back(i);
      if (j > 0) m.dof_parent.push_back(k - 1);
      else m.dof_parent.push_back(p < 0 ? -1 : m.idx_v[p] + m.nv_i[p] - 1);
    }
  }
  for (int k = 0; k < m.nbodies; ++k) {
    m.inertia_origin.push_back(m.inertia[k] + parallel_axis(m.mass[k], m.com[k]));  // I_η = I_cm − m c̃ c̃
  }
}

// depth-first positions of the DOFs: children in index order, each subtree one run
void depth_first(Model& m) {
  std::vector<std::vector<int>> children(m.nbodies);
  std::vector<int> roots;
  for (int i = 0; i < m.nbodies; ++i) (m.parent[i] < 0 ? roots : children[m.parent[i]]).push_back(i);
  m.dfs_begin.assign(m.nbodies, 0);
  m.dfs_end.assign(m.nbodies, 0);
  std::vector<std::pair<int, bool>> stack;  // (body, its subtree is done)
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, false});
  while (!stack.empty()) {
    const auto [i, done] = stack.back();
    stack.pop_back();
    if (done) {
      m.dfs_end[i] = int(m.dfs_dof.size());
      continue;
    }
    m.dfs_begin[i] = int(m.dfs_dof.size());
    for (int j = 0; j < m.nv_i[i]; ++j) m.dfs_dof.push_back(m.idx_v[i] + j);
    stack.push_back({i, true});
    for (auto it = children[i].rbegin(); it != children[i].rend(); ++it) stack.push_back({*it, false});
  }
}

// paths: body i continues its parent's when it is the parent's last child; chain and DOF runs
void paths(Model& m) {
  std::vector<int> last_child(m.nbodies, -1);
  for (int i = 0; i < m.nbodies; ++i)
    if (m.parent[i] >= 0) last_child[m.parent[i]] = i;
  m.path.assign(m.nbodies, 0);
  m.npaths = 0;
  for (int i = 0; i < m.nbodies; ++i) {
    const int p = m.parent[i];
    m.path[i] = p >= 0 && last_child[p] == i ? m.path[p] : m.npaths++;
  }
  m.chain = true;
  for (int k = 0; k < m.nv; ++k) {
    m.chain = m.chain && m.dof_parent[k] == k - 1;
    m.dof_run.push_back(k > 0 && m.dof_parent[k] == k - 1 ? m.dof_run[k - 1] : k);
  }
}

}  // namespace

Model Model::build(const std::vector<BodySpec>& given, const Vec3& gravity, InertiaCheck inertia_check) {
  if (!gravity.allFinite()) throw Error("gravity: expected finite numbers, got " + model_checks::fmt(gravity.transpose()));
  for (int i = 0; i < int(given.size()); ++i) model_checks::validate(given[i], i);

  Model m;
  const std::vector<BodySpec> specs = model_checks::triangle_inequality(given, inertia_check, m.warnings);
  m.gravity = gravity;
  std::vector<Target> target(specs.size());
  std::vector<int> spec_of;  // spec index of each model body
  for (int i = 0; i < int(specs.size()); ++i) {
    const BodySpec& b = specs[i];
    const Target parent_target = b.parent < 0 ? Target{} : target[b.parent];
    const Placement joint_in_target = compose(parent_target.X, b.placement);
    if (b.joint == JointType::Fixed) {
      weld(m, b, parent_target, joint_in_target, target[i]);
      continue;
    }
    target[i] = {m.nbodies, Placement{}};
    spec_of.push_back(i);
    add_body(m, b, parent_target.body, joint_in_target);
  }
  check_bodies(m, specs, spec_of);
  dof_tree(m);
  m.classify_joints();
  depth_first(m);
  paths(m);
  model_checks::check_mass_matrix(m, specs, spec_of);
  return m;
}

namespace {
std::vector<std::string> coordinate_names(const Model& m, bool of_q) {
  std::vector<std::string> names;
  for (int i = 0; i < m.nbodies; ++i) {
    const JointTraits& tr = joint_traits(m.joint_type[i]);
    for (const auto& suffix : of_q ? tr.q_labels : tr.v_labels)
      names.push_back(suffix.empty() ? m.joint_names[i] : m.joint_names[i] + "." + std::string(suffix));
  }
  return names;
}
}  // namespace

std::vector<std::string> Model::q_names() const { return coordinate_names(*this, true); }
std::vector<std::string> Model::v_names() const { return coordinate_names(*this, false); }

int Model::body_index(const std::string& name) const {
  for (int i = 0; i < nbodies; ++i)
    if (body_names[i] == name) return i;
  return -1;
}

int Model::joint_index(const std::string& name) const {
  for (int i = 0; i < nbodies; ++i)
    if (joint_names[i] == name) return i;
  return -1;
}

int Model::frame_index(const std::string& name) const {
  for (int f = 0; f < int(frame_names.size()); ++f)
    if (frame_names[f] == name) return f;
  return -1;
}

int Model::add_frame(const std::string& name, int body, const Placement& X) {
  const std::string where = "frame '" + printable(name) + "'";
  if (name.empty() || !is_valid_utf8(name)) throw Error(where + ": name: expected a non-empty UTF-8 name");
  if (frame_index(name) >= 0) throw Error(where + ": name: expected a new name, got one the model already has");
  if (body < -1 || body >= nbodies)
    throw Error(where + ": body: expected -1 (the world) .. " + std::to_string(nbodies - 1) + ", got " + std::to_string(body));
  if (!X.R.allFinite() || !X.p.allFinite()) throw Error(where + ": placement: expected finite numbers");
  if ((X.R.transpose() * X.R - Mat3::Identity()).norm() > 1e-9 || X.R.determinant() < 0)
    throw Error(where + ": placement rotation: expected a proper rotation matrix, got " + model_checks::fmt(X.R));
  frame_names.push_back(name);
  frame_body.push_back(body);
  frame_placement.push_back(X);
  return int(frame_names.size()) - 1;
}

void Model::classify_joints() {
  joint_model.clear();
  angles = {};
  for (int k = 0; k < nbodies; ++k) joint_model.push_back(classify_joint(joint_type[k], axis[k], placement[k].R, pitch[k]));
  for (const bool roots : {true, false})
    for (int k = 0; k < nbodies; ++k)
      if (turns_by_angle(joint_model[k]) && (parent[k] < 0) == roots) {
        angles.body.push_back(k);
        angles.q.push_back(idx_q[k]);
        angles.roots += roots;
      }
}

bool Model::has_free_joint() const {
  for (auto t : joint_type)
    if (t == JointType::Free) return true;
  return false;
}

bool Model::has_limits() const {
  for (size_t k = 0; k < lower.size(); ++k)
    if (std::isfinite(lower[k]) || std::isfinite(upper[k])) return true;
  return false;
}

bool Model::has_quaternions() const {
  for (int i = 0; i < nbodies; ++i)
    if (joint_quaternion(*this, i) >= 0) return true;
  return false;
}

VecX Model::neutral_configuration() const {
  VecX q(nq);
  for (int i = 0; i < nbodies; ++i) visit_joint(*this, i, [&](const auto& j) { j.neutral(q.data() + idx_q[i]); });
  return q;
}

void Model::normalize(Eigen::Ref<VecX> q) const {
  for (int i = 0; i < nbodies; ++i)
    if (const int k = joint_quaternion(*this, i); k >= 0) q.segment<4>(idx_q[i] + k).normalize();
}

void Model::check_unit_quaternions(const VecX& q, const std::string& where) const {
  if (q.size() != nq) return;  // the size is the caller's check, with its own words
  for (int i = 0; i < nbodies; ++i)
    if (const int k = joint_quaternion(*this, i); k >= 0) {
      const double norm = q.segment<4>(idx_q[i] + k).norm();
      if (!(std::abs(norm - 1.0) <= kUnitQuaternionTolerance))  // NaN too
        throw Error(where + ": joint '" + printable(joint_names[size_t(i)]) + "': expected a unit quaternion [w, x, y, z]" +
                    (k ? " after the position" : "") + " (norm within 1e-6 of 1, then normalized), got norm " +
                    short_number(norm));
    }
}

// q̇_i = T̄_i(q_i) v_i
void Model::qdot(const VecX& q, const VecX& v, Eigen::Ref<VecX> qd) const {
  for (int i = 0; i < nbodies; ++i)
    visit_joint(*this, i, [&](const auto& j) { j.qdot(q.data() + idx_q[i], v.data() + idx_v[i], qd.data() + idx_q[i]); });
}

VecX Model::velocity(const VecX& q, const VecX& qd) const {
  VecX v(nv);
  for (int i = 0; i < nbodies; ++i)
    visit_joint(*this, i, [&](const auto& j) { j.velocity(q.data() + idx_q[i], qd.data() + idx_q[i], v.data() + idx_v[i]); });
  return v;
}

VecX Model::integrate(const VecX& q, const VecX& v, double h) const {
  VecX out(nq);
  soadyn::integrate(*this, q, v, h, out);
  return out;
}

}  // namespace soadyn
