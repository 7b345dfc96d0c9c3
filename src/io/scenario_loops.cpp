// A scenario's closed loops (scenarios/README.md, loops.hpp): each loop's bodies or frames and its
// frames on them, and the initial state closed on the loops (assembled where the file's is not),
// its own and an MJCF model's (<equality connect/weld>) alike.
#include "scenario_reader.hpp"

#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/multibody/configuration.hpp"
#include "soadyn/sim/scenario.hpp"

#include <Eigen/Geometry>
#include <Eigen/QR>

namespace soadyn::scenario_detail {

namespace {

// a rotation whose z column is `axis` (unit): the frame of a hinge
Mat3 z_along(const Vec3& axis) { return Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), axis).toRotationMatrix(); }

// body `key` names (a body, a frame on one, or "world") and the placement of its point `at` on it
void place(const Reader& rd, const YAML::Node& key, const std::string& field, const Model& m, const Vec3& at, int& body,
           Placement& X) {
  const std::string name = rd.string(key, field);
  X.p = at;
  if (name == "world") {
    body = -1;
    return;
  }
  if (const auto it = std::find(m.body_names.begin(), m.body_names.end(), name); it != m.body_names.end()) {
    body = int(it - m.body_names.begin());
    return;
  }
  if (const int f = m.frame_index(name); f >= 0) {  // a frame (a link merged by a fixed joint): its body, at its place
    body = m.frame_body[size_t(f)];
    const Placement& F = m.frame_placement[size_t(f)];
    X.p = F.p + F.R * at;
    X.R = F.R;
    return;
  }
  std::vector<std::string> names = m.body_names;
  names.insert(names.end(), m.frame_names.begin(), m.frame_names.end());
  rd.fail(key, field, "no body or frame named '" + excerpt(name) + "'" + did_you_mean(name, names) + " (or 'world')");
}

LoopConstraint read_loop(const Reader& rd, const YAML::Node& e, const std::string& f, const Model& m, size_t k) {
  rd.keys(e, f, {"name", "type", "a", "at_a", "b", "at_b", "axis", "axis_b", "distance"});
  LoopConstraint c;
  c.name = e["name"] ? rd.string(e["name"], f + ".name") : "loop" + std::to_string(k + 1);
  const std::string type = rd.string(rd.require(e, "type", f), f + ".type");
  const std::vector<std::string> types = {"point", "hinge", "weld", "distance"};
  const auto t = std::find(types.begin(), types.end(), type);
  if (t == types.end()) rd.fail(e["type"], f + ".type", "expected point, hinge, weld or distance, got '" + excerpt(type) + "'" + did_you_mean(type, types));
  c.type = LoopType(t - types.begin());
  const Vec3 at_a = e["at_a"] ? rd.vec3(e["at_a"], f + ".at_a") : Vec3::Zero();
  const Vec3 at_b = e["at_b"] ? rd.vec3(e["at_b"], f + ".at_b") : Vec3::Zero();
  place(rd, rd.require(e, "a", f), f + ".a", m, at_a, c.body_a, c.at_a);
  YAML::Node world = YAML::Node("world");
  place(rd, e["b"] ? e["b"] : world, f + ".b", m, at_b, c.body_b, c.at_b);
  if (c.body_a == c.body_b) rd.fail(e, f, "a and b are the same body: a loop joins two");
  for (const char* key : {"axis", "axis_b"})
    if (e[key] && c.type != LoopType::Hinge) rd.fail(e[key], f + "." + key, "only a hinge has an axis");
  if (e["distance"] && c.type != LoopType::Distance) rd.fail(e["distance"], f + ".distance", "only a distance loop has a length");
  if (c.type == LoopType::Hinge) {
    // the axis in a's frame, and in b's (the same vector unless axis_b says otherwise)
    const auto axis = [&](const YAML::Node& n, const std::string& field) {
      const Vec3 v = rd.vec3(n, field);
      if (!(v.norm() > 1e-12)) rd.fail(n, field, "expected a nonzero axis");
      return Vec3(v.normalized());
    };
    const Vec3 a = e["axis"] ? axis(e["axis"], f + ".axis") : Vec3::UnitZ();
    const Vec3 b = e["axis_b"] ? axis(e["axis_b"], f + ".axis_b") : a;
    c.at_a.R = c.at_a.R * z_along(a);  // in the axes of the body or frame a names
    c.at_b.R = c.at_b.R * z_along(b);
  }
  if (c.type == LoopType::Distance && e["distance"]) c.distance = rd.positive(e["distance"], f + ".distance");
  return c;
}

}  // namespace

std::vector<char> held_dofs(const YAML::Node& initial, const char* part, const Model& m) {
  std::vector<char> held(size_t(m.nv), 0);
  if (!initial || !initial[part] || !initial[part].IsMap()) return held;
  for (auto it = initial[part].begin(); it != initial[part].end(); ++it)
    if (const int i = m.joint_index(it->first.Scalar()); i >= 0)
      for (int k = m.idx_v[i]; k < m.idx_v[i] + m.nv_i[i]; ++k) held[size_t(k)] = 1;
  return held;
}

void read_loops(const Reader& rd, const YAML::Node& n, const Model& m, const VecX& q0, std::vector<LoopConstraint>& out) {
  if (!n.IsSequence() || n.size() == 0) rd.fail(n, "loops", "expected a list of loops, got " + Reader::show(n));
  const size_t first = out.size();
  for (size_t k = 0; k < n.size(); ++k) out.push_back(read_loop(rd, n[k], "loops[" + std::to_string(k) + "]", m, k));
  // a distance loop without a length: the frames' distance at the initial state
  Data d(m);
  update_kinematics(m, d, q0);
  for (size_t k = first; k < out.size(); ++k)
    if (LoopConstraint& c = out[k]; c.type == LoopType::Distance && c.distance == 0.0)
      c.distance = (body_frame_placement(m, d, c.body_a, c.at_a).p - body_frame_placement(m, d, c.body_b, c.at_b).p).norm();
}

double close_on_loops(const Model& m, const std::vector<LoopConstraint>& loops, const std::vector<char>& hold_q,
                      const std::vector<char>& hold_v, VecX& q0, VecX& v0) {
  // q₀ closed by Newton on φ over the DOFs not held (steps of minimum norm)
  Data d(m);
  LoopData ld(m, loops);
  std::vector<int> free;
  for (int k = 0; k < m.nv; ++k)
    if (!hold_q[size_t(k)]) free.push_back(k);
  double error = 0.0;
  for (int it = 0; it < 50; ++it) {
    update_kinematics(m, d, q0);
    update_velocities(m, d, VecX::Zero(m.nv));
    loop_rows(m, d, loops, ld);
    error = ld.phi.size() ? ld.phi.cwiseAbs().maxCoeff() : 0.0;
    if (error <= kLoopClosure || free.empty()) break;
    const VecX step = -Eigen::CompleteOrthogonalDecomposition<MatX>(ld.K(Eigen::all, free)).solve(ld.phi);
    VecX delta = VecX::Zero(m.nv);
    for (size_t j = 0; j < free.size(); ++j) delta(free[j]) = step(Eigen::Index(j));
    q0 = m.integrate(q0, delta, 1.0);
  }
  if (error > kLoopClosure) return error;
  // v₀ onto K v = 0 over the DOFs not held
  std::vector<int> moving;
  for (int k = 0; k < m.nv; ++k)
    if (!hold_v[size_t(k)]) moving.push_back(k);
  if (!moving.empty()) {
    const VecX correction = Eigen::CompleteOrthogonalDecomposition<MatX>(ld.K(Eigen::all, moving)).solve(VecX(ld.K * v0));
    for (size_t j = 0; j < moving.size(); ++j) v0(moving[j]) -= correction(Eigen::Index(j));
  }
  return error;
}

void assemble_loops(const Reader& rd, const YAML::Node& where, const std::string& field, const YAML::Node& initial,
                    const Model& m, const std::vector<LoopConstraint>& loops, VecX& q0, VecX& v0) {
  const double error = close_on_loops(m, loops, held_dofs(initial, "q", m), held_dofs(initial, "qd", m), q0, v0);
  if (error > kLoopClosure)
    rd.fail(where, field, "the initial state cannot be closed on the loops (largest closure error " + Reader::show_number(error) +
                              " after 50 Newton steps with the joints initial.q names held): check the loops' points and the initial angles");
}

std::string assembly_note(const Model& m, const VecX& q_file, const VecX& v_file, const VecX& q0, const VecX& v0) {
  // the largest move of each, δ = q0 ⊖ q_file along the tangent, and its joint
  const VecX dq = difference(m, q_file, q0), dv = v0 - v_file;
  Eigen::Index kq = 0, kv = 0;
  const double mq = dq.size() ? dq.cwiseAbs().maxCoeff(&kq) : 0.0, mv = dv.size() ? dv.cwiseAbs().maxCoeff(&kv) : 0.0;
  if (mq <= 1e-12 && mv <= 1e-12) return "";
  const auto joint_of = [&](Eigen::Index k) { return m.joint_names[size_t(m.dof_body[size_t(k)])]; };
  std::string out = "loops: the initial state was assembled onto the loops";
  if (mq > 1e-12) out += ": q moved by up to " + Reader::show_number(mq) + " (joint '" + joint_of(kq) + "')";
  if (mv > 1e-12) out += std::string(mq > 1e-12 ? ", " : ": ") + "v by up to " + Reader::show_number(mv) + " (joint '" + joint_of(kv) + "')";
  return out + "; the joints initial.q and initial.qd name were held";
}

}  // namespace soadyn::scenario_detail
