// MuJoCo's equality constraints as soadyn's loops (loops.hpp).  MuJoCo 2.2's compiled eq_data,
// bodies 1 and 2 at (x₁, R₁) and (x₂, R₂) in the world:
//   connect  [anchor₁ (3), anchor₂ (3)]: x₁ + R₁ anchor₁ = x₂ + R₂ anchor₂, anchor₂ the compiler's
//            (body 1's anchor in body 2's frame at qpos0)
//   weld     [anchor (3), relpos (3), relquat (4), torquescale]: x₁ + R₁ relpos = x₂ + R₂ anchor and
//            R₁ R(relquat) = R₂ (relpose the compiler's, the pose at qpos0, unless the file gives
//            one); torquescale scales the rotation rows' Jacobian (their force in MuJoCo's soft
//            constraint, not where it holds), 0 dropping them
// so a connect is a point loop from (body 1, anchor₁) to (body 2, anchor₂), a weld a weld loop
// from body 1's frame (relquat, relpos) to body 2's (identity, anchor), a point loop with
// torquescale 0.  soadyn holds them exactly: MuJoCo's solref/solimp (how softly) are not modelled.
#include "mjcf_equality.hpp"

#include <Eigen/Geometry>

#include <set>

namespace soadyn::mjcf_detail {

namespace {

Mat3 rotation(const mjtNum* quat) {  // MuJoCo's (w, x, y, z)
  return Eigen::Quaterniond(quat[0], quat[1], quat[2], quat[3]).normalized().toRotationMatrix();
}
Vec3 vec3(const mjtNum* x) { return Vec3(x[0], x[1], x[2]); }

// "n what" / "n whats"
std::string counted(int n, const std::string& one, const std::string& many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

}  // namespace

EqualityLoops equality_loops(const mjModel* m, const PlaceOnModel& place) {
  EqualityLoops out;
  int inactive = 0, joint = 0, tendon = 0, other = 0, rigid = 0;
  std::set<std::string> names;  // the file's names first: a generated one never takes one of them
  for (int i = 0; i < m->neq; ++i)
    if (const char* n = mj_id2name(m, mjOBJ_EQUALITY, i); n && *n) names.insert(n);
  for (int i = 0; i < m->neq; ++i) {
    const int type = m->eq_type[i];
    if (!m->eq_active[i]) {
      ++inactive;
      continue;
    }
    if (type != mjEQ_CONNECT && type != mjEQ_WELD) {
      ++(type == mjEQ_JOINT ? joint : type == mjEQ_TENDON ? tendon : other);
      continue;
    }
    const mjtNum* d = m->eq_data + size_t(mjNEQDATA) * size_t(i);
    LoopConstraint c;
    Placement on_1, on_2;  // in MuJoCo's bodies 1 and 2
    if (type == mjEQ_CONNECT) {
      on_1.p = vec3(d);
      on_2.p = vec3(d + 3);
    } else {
      c.type = d[10] != 0.0 ? LoopType::Weld : LoopType::Point;
      on_1 = Placement{rotation(d + 6), vec3(d + 3)};
      on_2.p = vec3(d);
    }
    c.at_a = place(m->eq_obj1id[i], on_1, c.body_a);
    c.at_b = place(m->eq_obj2id[i], on_2, c.body_b);
    if (c.body_a == c.body_b) {  // both on one rigid body (or the world): its forces cancel
      ++rigid;
      continue;
    }
    const char* n = mj_id2name(m, mjOBJ_EQUALITY, i);
    c.name = n && *n ? std::string(n) : "equality" + std::to_string(i);
    for (int k = 2; !(n && *n) && !names.insert(c.name).second; ++k) c.name = "equality" + std::to_string(i) + "~" + std::to_string(k);
    out.loops.push_back(std::move(c));
  }
  const auto note = [&](int n, const std::string& one, const std::string& many) {
    if (n > 0) out.ignored.push_back(counted(n, one, many));
  };
  note(inactive, "inactive equality constraint", "inactive equality constraints");
  note(joint, "joint equality constraint", "joint equality constraints");
  note(tendon, "tendon equality constraint", "tendon equality constraints");
  note(other, "equality constraint of another kind", "equality constraints of other kinds");
  note(rigid, "equality constraint within one rigid body (no effect)", "equality constraints within one rigid body (no effect)");
  if (const int held = int(out.loops.size()); held > 0)
    out.ignored.push_back("the solref/solimp softness of " + counted(held, "equality constraint (held exactly as a loop)",
                                                                     "equality constraints (held exactly as loops)"));
  return out;
}

}  // namespace soadyn::mjcf_detail
