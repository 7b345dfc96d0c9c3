#include "soadyn/model.hpp"

#include "soadyn/inertia.hpp"
#include "soadyn/text.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace soadyn {

namespace {

std::string fmt(double x) {
  std::ostringstream os;
  os.precision(10);
  os << x;
  return os.str();
}

std::string fmt(const Eigen::MatrixXd& m) {
  std::ostringstream os;
  os.precision(10);
  os << "[";
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    if (r) os << "; ";
    for (Eigen::Index c = 0; c < m.cols(); ++c) os << (c ? " " : "") << m(r, c);
  }
  os << "]";
  return os.str();
}

[[noreturn]] void refuse(const BodySpec& b, int i, const std::string& field, const std::string& expected,
                         const std::string& got) {
  throw ModelError(i, "body '" + printable(b.name) + "' (index " + std::to_string(i) + ")",
                   field + ": expected " + expected + ", got " + got);
}

void check_finite(const BodySpec& b, int i, const std::string& field, const Eigen::MatrixXd& m) {
  if (!m.allFinite()) refuse(b, i, field, "finite numbers", fmt(m));
}

// Mass properties of one rigid body (or one part of one): symmetric and positive semidefinite,
// each up to round-off.  A part may be a point mass (zero inertia), a thin rod (one zero principal
// moment) or, without mass, a bare frame.  The triangle inequality is triangle_excess's (below).
void check_inertia(const BodySpec& b, int i, double mass, const Mat3& I) {
  if (mass == 0.0) {
    if (!I.isZero(0.0)) refuse(b, i, "mass", "a positive mass for a body with inertia " + fmt(I), "0");
    return;
  }
  const double scale = I.cwiseAbs().maxCoeff();
  if ((I - I.transpose()).cwiseAbs().maxCoeff() > 1e-9 * std::max(scale, 1e-300))
    refuse(b, i, "inertia", "a symmetric matrix", fmt(I));
  const Eigen::SelfAdjointEigenSolver<Mat3> es(0.5 * (I + I.transpose()), Eigen::EigenvaluesOnly);
  const Vec3 l = es.eigenvalues();  // ascending
  if (!l.allFinite())
    refuse(b, i, "inertia", "principal moments a double can hold",
           "an overflow computing them (mass " + fmt(mass) + ", inertia " + fmt(I) + ")");
  if (l(0) < -1e-9 * std::abs(l(2)) || !(l(2) >= 0.0))
    refuse(b, i, "inertia", "a positive semidefinite matrix (principal moments >= 0)",
           "principal moments " + fmt(l.transpose()));
}

// Triangle inequality of the principal moments l0 <= l1 <= l2 (each at most the sum of the
// others): the excess (l2 − l0 − l1)/(l0 + l1), 0 when it holds up to round-off.
double triangle_excess(const Vec3& l) {
  if (!(l(2) > (l(0) + l(1)) * (1.0 + 1e-9) + 1e-9 * l(2))) return 0.0;
  return l(0) + l(1) > 0.0 ? (l(2) - l(0) - l(1)) / (l(0) + l(1)) : std::numeric_limits<double>::infinity();
}

std::string percent(double r) {
  if (!std::isfinite(r)) return "both others zero";
  std::ostringstream os;
  os.precision(2);
  os << std::fixed << 100.0 * r << " %";
  return os.str();
}

// The triangle inequality over every body part at once (a sum of parts that obey it obeys it, so
// the merged bodies need no second look): each violation is warned of, balanced or refused as
// `check` says, and one message names every offending body.  Balancing raises the two smaller
// principal moments by half the excess each, about the same principal axes: the nearest
// physical inertia that keeps the largest moment.
std::vector<BodySpec> triangle_inequality(const std::vector<BodySpec>& specs, InertiaCheck check,
                                          std::vector<std::string>& warnings) {
  std::vector<BodySpec> out = specs;
  std::string listed, refused;
  int first_refused = -1, n_listed = 0;
  for (int i = 0; i < int(specs.size()); ++i) {
    const BodySpec& b = specs[i];
    if (b.mass == 0.0) continue;
    const Eigen::SelfAdjointEigenSolver<Mat3> es(0.5 * (b.inertia + b.inertia.transpose()));
    const Vec3 l = es.eigenvalues();
    const double r = triangle_excess(l);
    if (r == 0.0) continue;
    const std::string item = "'" + printable(b.name) + "' " + fmt(l.transpose()) + " (+" + percent(r) + ")";
    const bool refuse_it = check == InertiaCheck::Strict ||
                           (check == InertiaCheck::Warn && !(r <= kTriangleTolerance));
    if (refuse_it) {
      refused += (refused.empty() ? "" : ", ") + item;
      if (first_refused < 0) first_refused = i;
      continue;
    }
    listed += (n_listed++ ? ", " : "") + item;
    if (check == InertiaCheck::Balance) {
      const double e = l(2) - l(0) - l(1);
      const Vec3 lb(l(0) + 0.5 * e, l(1) + 0.5 * e, l(2));
      out[i].inertia = es.eigenvectors() * lb.asDiagonal() * es.eigenvectors().transpose();
    }
  }
  if (first_refused >= 0)
    throw ModelError(first_refused, "body '" + printable(specs[first_refused].name) + "' (index " +
                                        std::to_string(first_refused) + ")",
                     "inertia: expected principal moments obeying the triangle inequality (largest <= sum "
                     "of the others" + std::string(check == InertiaCheck::Warn ? ", within " + percent(kTriangleTolerance) : "") +
                     "), got " + refused +
                     (check == InertiaCheck::Strict ? "" : "; --inertia-check balance (a scenario's inertia_check: balance) makes them physical"));
  if (n_listed)
    warnings.push_back(std::string(check == InertiaCheck::Balance ? "balanced" : "loaded as given") + " " +
                       std::to_string(n_listed) + (n_listed == 1 ? " inertia" : " inertias") +
                       " breaking the triangle inequality (largest principal moment > sum of the others): " + listed);
  return out;
}

// The checks every user-supplied body must pass.
void validate(const BodySpec& b, int i) {
  // names go into UTF-8 attributes of the logs and into messages
  if (!is_valid_utf8(b.name)) refuse(b, i, "name", "a valid UTF-8 name", "'" + printable(b.name) + "'");
  if (!is_valid_utf8(b.joint_name))
    refuse(b, i, "joint", "a valid UTF-8 name", "'" + printable(b.joint_name) + "'");
  if (b.parent < -1 || b.parent >= i)
    refuse(b, i, "parent", "a body listed before it (index -1.." + std::to_string(i - 1) + ")",
           std::to_string(b.parent));
  check_finite(b, i, "mass", Eigen::Matrix<double, 1, 1>::Constant(b.mass));
  check_finite(b, i, "centre of mass", b.com);
  check_finite(b, i, "inertia", b.inertia);
  check_finite(b, i, "axis", b.axis);
  check_finite(b, i, "placement rotation", b.placement.R);
  check_finite(b, i, "placement translation", b.placement.p);
  // magnitudes whose products in 𝓜 (m r² summed over a tree of any size) stay far below overflow:
  // beyond these a double cannot hold the model's mass matrix, so it would come out inf or NaN
  constexpr double max_mass = 1e50, max_length = 1e50, max_inertia = 1e150;
  if (std::abs(b.mass) > max_mass) refuse(b, i, "mass", "at most 1e50 kg", fmt(b.mass));
  if (b.com.cwiseAbs().maxCoeff() > max_length)
    refuse(b, i, "centre of mass", "coordinates within 1e50 m", fmt(b.com.transpose()));
  if (b.placement.p.cwiseAbs().maxCoeff() > max_length)
    refuse(b, i, "placement translation", "coordinates within 1e50 m", fmt(b.placement.p.transpose()));
  if (b.inertia.cwiseAbs().maxCoeff() > max_inertia)
    refuse(b, i, "inertia", "entries of at most 1e150 kg m^2", fmt(b.inertia));
  // a part may be massless; the moving body it belongs to is checked once merged
  if (!(b.mass >= 0.0))
    refuse(b, i, "mass", b.joint == JointType::Fixed ? "a mass >= 0" : "a positive mass", fmt(b.mass));
  const Mat3 R = b.placement.R;
  if ((R.transpose() * R - Mat3::Identity()).norm() > 1e-9 || R.determinant() < 0)
    refuse(b, i, "placement rotation", "a proper rotation matrix", fmt(R));
  const JointTraits& tr = joint_traits(b.joint);
  if (tr.has_axis && (!(b.axis.norm() > 1e-12) || !std::isfinite(b.axis.squaredNorm())))
    refuse(b, i, "axis", "a non-zero vector of norm between 1e-12 and 1e150", fmt(b.axis.transpose()));
  if (tr.root_only) {
    if (b.parent != -1) refuse(b, i, "joint", "a free joint only at a root (parent = ground)", "a parent");
    if (!b.placement.R.isIdentity(1e-12) || !b.placement.p.isZero(0.0))
      refuse(b, i, "placement", "none for a free joint (its q is the body's pose in the world)",
             "a non-identity placement");
  }
  // travel: NaN never, lower ≤ upper (equal: the joint cannot move, which a fixed joint says)
  if (std::isnan(b.lower) || std::isnan(b.upper) || !(b.lower < b.upper))
    refuse(b, i, "limits", "lower < upper (not NaN)", fmt(b.lower) + " .. " + fmt(b.upper));
  if (!(b.effort > 0)) refuse(b, i, "effort", "a force or torque > 0 (inf: none)", fmt(b.effort));
  check_inertia(b, i, b.mass, b.inertia);
}

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

// Names DOF k: the joint's name, and for a multi-DOF joint which of its DOFs.
std::string dof_name(const Model& m, int k) {
  const int i = m.dof_body[k];
  std::string name = "DOF " + std::to_string(k) + " (joint '" + m.joint_names[i] + "'";
  if (m.nv_i[i] > 1) name += ", its DOF " + std::to_string(k - m.idx_v[i]);
  return name + ")";
}

// 𝓜 is positive definite iff every pivot of its innovations factorization 𝓜 = (I + K) D (I + K)ᵀ
// is: D_k = g_kᵀ P_k g_k, with P_k the articulated inertia of DOF k's subtree.  At the neutral
// configuration every joint motion is the identity, so the frames follow from the placements.
// Sweep tip to base, P about each body's joint point η_i in world axes, one DOF at a time:
//   P_i = M_i + Σ_children Φᵀ P_c⁺ Φ,   Φ = [e 0; −d̃ e], d = η_c − η_i,
//   P⁺ = P − P g gᵀ P / (gᵀ P g) for each of the joint's columns g, last first.
// D_k is the body's own inertia along g plus what its children's P⁺ add; each is a difference
// whose terms are bounded by the body's mass moments and by the children's P before their
// projections.  A pivot below 1e-12 of that size is round-off: the DOF carries no inertia.
//
// The library's composite sweep (mass_matrix.cpp) keeps K_i about the joint point η_i and moves
// each column to the world origin once, so 𝓜_kk comes out of terms that cancel down to its size:
// K_i's own, of size S = Σ_{j ⊆ subtree} tr I_j + m_j r_j² (r_j: the reach of body j's centre of
// mass from η_i, under any revolute turn), and the world shift's, of size |η_i| |f| with
// |f| ≤ T |g_ω| + U |g_v|, T = Σ m_j r_j, U = Σ m_j.  Their round-off
//   e_k = 8 ε (S |g_ω|² + 2 T |g_ω| |g_v| + U |g_v|² + 2 ρ_i |g_ω| (T |g_ω| + U |g_v|)),
// ρ_i the joint's reach from the world origin, must stay below 1e-6 𝓜_kk (each diagonal entry to
// six digits), and their sum below 1e-9 of the largest (so that no eigenvalue of the computed 𝓜
// strays below −1e-9 λ_max).  A model too spread out for a double (a 1 kg arm hung 1e30 m along
// the axis it turns about) is refused, where its 𝓜 would come out indefinite.  𝓜_kk = gᵀ C_i g
// here, C_i the composite inertia about η_i, whose entries are formed without that cancellation.
// Prismatic travel and a free root's position are the configuration's, and not bounded here.
void check_mass_matrix(const Model& m, const std::vector<BodySpec>& specs, const std::vector<int>& spec_of) {
  std::vector<Mat3> R(m.nbodies);
  std::vector<Vec3> eta(m.nbodies), s(m.nbodies);
  std::vector<Mat6> P(m.nbodies), below(m.nbodies, Mat6::Zero());  // below: Σ Φᵀ P_c Φ before projecting
  std::vector<Mat6> C(m.nbodies);                                   // composite inertia about η_i
  std::vector<double> reach(m.nbodies), S(m.nbodies), T(m.nbodies), U(m.nbodies);  // S, T, U about η_i
  for (int i = 0; i < m.nbodies; ++i) {
    const int p = m.parent[i];
    const Mat3 Rp = p < 0 ? Mat3::Identity() : R[p];
    R[i] = Rp * m.placement[i].R;
    eta[i] = (p < 0 ? Vec3::Zero() : eta[p]) + Rp * m.placement[i].p;
    s[i] = R[i] * m.com[i];
    P[i] = SpatialInertia::from_body(m.mass[i], s[i], R[i] * m.inertia[i] * R[i].transpose()).matrix();
    C[i] = P[i];
    reach[i] = (p < 0 ? 0.0 : reach[p]) + m.placement[i].p.norm();
    const double r = m.com[i].norm();
    S[i] = m.inertia[i].trace() + m.mass[i] * r * r, T[i] = m.mass[i] * r, U[i] = m.mass[i];
  }
  std::vector<int> singular;
  int coarse = -1;  // the first DOF whose 𝓜_kk the world-coordinate round-off swamps
  double coarse_diagonal = 0, coarse_error = 0, total_error = 0, largest = 0;
  for (int i = m.nbodies - 1; i >= 0; --i) {
    Mat6X G(6, m.nv_i[i]);
    joint_subspace(m.joint_type[i], m.axis[i], R[i], R[i], G);  // at the neutral configuration Rb = Rj
    const Mat6 before = P[i];
    const double mi = m.mass[i], ms = mi * s[i].norm(), rot = m.inertia[i].trace() + 2.0 * ms * s[i].norm();
    for (int j = m.nv_i[i] - 1; j >= 0; --j) {
      const Vec6 g = G.col(j), Pg = P[i] * g;
      const double gw = g.head<3>().norm(), gv = g.tail<3>().norm();
      const double size = rot * gw * gw + 2.0 * ms * gw * gv + mi * gv * gv + g.dot(below[i] * g);
      const double pivot = g.dot(Pg);
      const double error = 8 * std::numeric_limits<double>::epsilon() *
                           (S[i] * gw * gw + 2 * T[i] * gw * gv + U[i] * gv * gv +
                            2 * reach[i] * gw * (T[i] * gw + U[i] * gv));
      if (pivot > 1e-12 * size) P[i] -= Pg * Pg.transpose() / pivot;
      else singular.push_back(m.idx_v[i] + j);
      const double diagonal = g.dot(C[i] * g);
      total_error += error, largest = std::max(largest, diagonal);
      if (!(error <= 1e-6 * diagonal)) coarse = m.idx_v[i] + j, coarse_diagonal = diagonal, coarse_error = error;
    }
    if (const int p = m.parent[i]; p >= 0) {
      Mat6 Phi = Mat6::Identity();
      Phi.bottomLeftCorner<3, 3>() = -skew(eta[i] - eta[p]);
      P[p] += Phi.transpose() * P[i] * Phi;
      below[p] += Phi.transpose() * before * Phi;
      C[p] += Phi.transpose() * C[i] * Phi;
      // about η_p the subtree's bodies reach at most L = |placement| further: (r + L)² expanded
      const double L = m.placement[i].p.norm();
      S[p] += S[i] + 2 * L * T[i] + L * L * U[i], T[p] += T[i] + L * U[i], U[p] += U[i];
    }
  }
  if (singular.empty() && (coarse >= 0 || !(total_error <= 1e-9 * largest))) {
    double far = 0;
    for (int i = 0; i < m.nbodies; ++i) far = std::max(far, reach[i] + m.com[i].norm());
    const std::string from = " from bodies up to " + fmt(far) + " m from the world origin";
    if (coarse < 0)
      refuse(specs[spec_of[0]], spec_of[0], "mass matrix",
             "lengths a double resolves (round-off below 1e-9 of the largest diagonal entry)",
             "round-off " + fmt(total_error) + " against " + fmt(largest) + from);
    const int first = spec_of[m.dof_body[coarse]];
    refuse(specs[first], first, "mass matrix",
           "lengths a double resolves against each DOF's inertia (round-off below 1e-6 of it)",
           dof_name(m, coarse) + " swamped by round-off " + fmt(coarse_error) + " (against " +
               fmt(coarse_diagonal) + ")" + from);
  }
  if (singular.empty()) return;
  std::sort(singular.begin(), singular.end());
  std::string got;
  for (size_t n = 0; n < singular.size() && n < 6; ++n) got += (n ? ", " : "") + dof_name(m, singular[n]);
  if (singular.size() > 6) got += " and " + std::to_string(singular.size() - 6) + " more";
  const int first = spec_of[m.dof_body[singular.front()]];
  refuse(specs[first], first, "mass matrix",
         "positive definite at the neutral configuration",
         "singular: no inertia on " + got);
}

}  // namespace

Model Model::build(const std::vector<BodySpec>& given, const Vec3& gravity, InertiaCheck inertia_check) {
  if (!gravity.allFinite()) throw Error("gravity: expected finite numbers, got " + fmt(gravity.transpose()));
  for (int i = 0; i < int(given.size()); ++i) validate(given[i], i);

  Model m;
  const std::vector<BodySpec> specs = triangle_inequality(given, inertia_check, m.warnings);
  m.gravity = gravity;
  std::vector<Target> target(specs.size());
  std::vector<int> spec_of;  // spec index of each model body
  for (int i = 0; i < int(specs.size()); ++i) {
    const BodySpec& b = specs[i];
    const Target parent_target = b.parent < 0 ? Target{} : target[b.parent];
    const Placement joint_in_target = compose(parent_target.X, b.placement);
    if (b.joint == JointType::Fixed) {
      // welded: merge mass properties into the parent's model body (or the world)
      target[i] = {parent_target.body, joint_in_target};
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
      continue;
    }
    const int k = m.nbodies++;
    target[i] = {k, Placement{}};
    m.frame_names.push_back(b.name);
    m.frame_body.push_back(k);
    m.frame_placement.emplace_back();
    spec_of.push_back(i);
    m.parent.push_back(parent_target.body);
    m.joint_type.push_back(b.joint);
    m.axis.push_back(joint_traits(b.joint).has_axis ? Vec3(b.axis.normalized()) : Vec3::Zero());
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
  // frame that moving bodies hang from (one of several joints in one MJCF body, a bare gimbal
  // ring), which the positive definiteness of 𝓜 below then decides
  std::vector<char> has_child(size_t(m.nbodies), 0);
  for (int k = 0; k < m.nbodies; ++k)
    if (m.parent[k] >= 0) has_child[size_t(m.parent[k])] = 1;
  for (int k = 0; k < m.nbodies; ++k) {
    BodySpec merged = specs[spec_of[k]];
    merged.inertia = m.inertia[k];
    if (!std::isfinite(m.mass[k]) || !m.inertia[k].allFinite())
      refuse(merged, spec_of[k], "mass", "welded bodies whose combined inertia a double can hold",
             "an overflow (not finite) merging their masses and inertias about the joint frame");
    if (m.mass[k] == 0.0 && has_child[size_t(k)] && m.inertia[k].isZero(0.0)) continue;
    if (!(m.mass[k] > 0.0))
      refuse(merged, spec_of[k], "mass",
             "a positive mass for a moving body" +
                 std::string(m.merged_names[k].empty() ? "" : " (with the bodies welded to it)"),
             fmt(m.mass[k]));
    check_inertia(merged, spec_of[k], m.mass[k], m.inertia[k]);
  }

  // DOF tree for the LᵀDL factorization: λ(k) and the depth (nilpotency of Φ_D)
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
    int unit = 0;
    const JointType t = m.joint_type[k];
    if (t == JointType::Revolute || t == JointType::Prismatic)
      for (int a = 0; a < 3; ++a) {
        if (m.axis[k] == Vec3::Unit(a)) unit = a + 1;
        if (m.axis[k] == -Vec3::Unit(a)) unit = -(a + 1);
      }
    m.unit_axis.push_back(unit);
    m.placement_turns.push_back(m.placement[k].R != Mat3::Identity());
    m.has_planar = m.has_planar || t == JointType::Planar;
  }
  for (const bool roots : {true, false})
    for (int k = 0; k < m.nbodies; ++k)
      if (m.unit_axis[k] != 0 && m.joint_type[k] == JointType::Revolute && (m.parent[k] < 0) == roots) {
        m.turn_body.push_back(k);
        m.turn_q.push_back(m.idx_q[k]);
        m.turn_roots += roots;
      }
  // depth-first positions of the DOFs: children in index order, each subtree one run
  {
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
  m.chain = true;
  for (int k = 0; k < m.nv; ++k) {
    m.chain = m.chain && m.dof_parent[k] == k - 1;
    m.dof_run.push_back(k > 0 && m.dof_parent[k] == k - 1 ? m.dof_run[k - 1] : k);
  }
  check_mass_matrix(m, specs, spec_of);
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
    throw Error(where + ": placement rotation: expected a proper rotation matrix, got " + fmt(X.R));
  frame_names.push_back(name);
  frame_body.push_back(body);
  frame_placement.push_back(X);
  return int(frame_names.size()) - 1;
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
  for (auto t : joint_type)
    if (joint_traits(t).quaternion >= 0) return true;
  return false;
}

VecX Model::neutral_configuration() const {
  VecX q(nq);
  for (int i = 0; i < nbodies; ++i) joint_neutral(joint_type[i], q.data() + idx_q[i]);
  return q;
}

void Model::normalize(Eigen::Ref<VecX> q) const {
  for (int i = 0; i < nbodies; ++i)
    if (const int k = joint_traits(joint_type[i]).quaternion; k >= 0) q.segment<4>(idx_q[i] + k).normalize();
}

void Model::qdot(const VecX& q, const VecX& v, Eigen::Ref<VecX> qd) const {
  for (int i = 0; i < nbodies; ++i)
    joint_qdot(joint_type[i], q.data() + idx_q[i], v.data() + idx_v[i], qd.data() + idx_q[i]);
}

VecX Model::velocity(const VecX& q, const VecX& qd) const {
  VecX v(nv);
  for (int i = 0; i < nbodies; ++i)
    joint_velocity(joint_type[i], q.data() + idx_q[i], qd.data() + idx_q[i], v.data() + idx_v[i]);
  return v;
}

VecX Model::integrate(const VecX& q, const VecX& v, double h) const {
  VecX out(nq);
  for (int i = 0; i < nbodies; ++i)
    joint_integrate(joint_type[i], q.data() + idx_q[i], v.data() + idx_v[i], h, out.data() + idx_q[i]);
  return out;
}

}  // namespace soadyn
