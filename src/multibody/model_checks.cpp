// The checks a model's bodies and the model itself must pass before Model::build returns it
// (model_checks.hpp): finite numbers, mass properties, joint data, the triangle inequality, and a
// mass matrix that is positive definite and resolvable in doubles at the neutral configuration.
#include "model_checks.hpp"

#include "articulated_inertia.hpp"

#include "soadyn/multibody/inertia.hpp"
#include "soadyn/multibody/text.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace soadyn::model_checks {

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
  if (b.joint == JointType::Helical && !std::isfinite(b.pitch))
    refuse(b, i, "pitch", "a finite pitch in m/rad", fmt(b.pitch));
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
// Sweep tip to base, P about each body's joint point η_i in world axes, one DOF at a time, with
// the articulated-body route's own two steps (articulated_inertia.hpp):
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
    joint_subspace(m.joint_type[i], m.axis[i], R[i], R[i], G, m.pitch[i]);  // at the neutral configuration Rb = Rj
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
      if (pivot > 1e-12 * size) articulated_inertia::remove_column(P[i], Pg, 1.0 / pivot);
      else singular.push_back(m.idx_v[i] + j);
      const double diagonal = g.dot(C[i] * g);
      total_error += error, largest = std::max(largest, diagonal);
      if (!(error <= 1e-6 * diagonal)) coarse = m.idx_v[i] + j, coarse_diagonal = diagonal, coarse_error = error;
    }
    if (const int p = m.parent[i]; p >= 0) {
      const Vec3 d = eta[i] - eta[p];
      articulated_inertia::add_to_parent(P[p], P[i], d);
      articulated_inertia::add_to_parent(below[p], before, d);
      articulated_inertia::add_to_parent(C[p], C[i], d);
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

}  // namespace soadyn::model_checks
