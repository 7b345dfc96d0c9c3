// Derivatives of inverse and forward dynamics: against central differences along the tangent
// (q ⊕ δ, the convention of derivatives.hpp) on seeded random trees with free roots, prismatic,
// planar and ball joints; against −𝓜⁻¹ ∂τ/∂x with a dense 𝓜 from the note's literal procedure;
// and against the closed forms of the note's Example 1 (a pendulum on a cart).
#include "soadyn/algorithm/derivatives.hpp"

#include "test_util.hpp"

#include <Eigen/LU>

using namespace soadyn;
using namespace soadyn::test;

namespace {

using Case = TreeCase;

const Case kCases[] = {
    {"chain6", {.n = 6, .branching = 0.0}},
    {"tree12_prismatic", {.n = 12, .branching = 0.6, .prismatic = 0.4}},
    {"tree12_ball", {.n = 12, .branching = 0.5, .ball = 0.4}},
    {"tree12_planar", {.n = 12, .branching = 0.5, .prismatic = 0.2, .planar = 0.4}},
    {"free_tree15_mixed", {.n = 15, .branching = 0.5, .prismatic = 0.2, .ball = 0.25, .planar = 0.15, .free_root = true}},
    {"free_chain10_ball", {.n = 10, .branching = 0.0, .ball = 0.5, .free_root = true}},
    {"free_alone", {.n = 1, .free_root = true}},
    {"fixed_tree14", {.n = 14, .branching = 0.5, .prismatic = 0.2, .ball = 0.2, .free_root = true, .fixed = 4}},
    {"tree12_helical", {.n = 12, .branching = 0.5, .prismatic = 0.1, .ball = 0.2, .helical = 0.5, .free_root = true}},
};

// q ⊕ h e_c: the tangent perturbation of derivatives.hpp
VecX perturbed(const Model& m, const VecX& q, int c, double h) {
  VecX d = VecX::Zero(m.nv);
  d(c) = h;
  return m.integrate(q, d, 1.0);
}

VecX tau_at(const Model& m, Data& d, const VecX& q, const VecX& v, const VecX& qdd) {
  update_kinematics(m, d, q);
  update_velocities(m, d, v);
  inverse_dynamics(m, d, qdd);
  return d.tau;
}

// q̈ by the O(N) articulated-body route: independent of the LᵀDL factor the derivatives use
VecX qdd_at(const Model& m, Data& d, const Inputs& in, const VecX& q, const VecX& v, const VecX& tau0) {
  update_kinematics(m, d, q);
  update_velocities(m, d, v);
  VecX tau(m.nv);
  in.evaluate(0.0, q, v, tau);
  tau += tau0;
  forward_dynamics(m, d, tau, FdMethod::ArticulatedBody);
  return d.qdd;
}

// central differences of g along the tangent of q and along v
template <class G>
void central(const Model& m, const VecX& q, const VecX& v, G&& g, MatX& dq, MatX& dv, double h = 1e-5) {
  dq.resize(m.nv, m.nv);
  dv.resize(m.nv, m.nv);
  for (int c = 0; c < m.nv; ++c) {
    dq.col(c) = (g(perturbed(m, q, c, h), v) - g(perturbed(m, q, c, -h), v)) / (2 * h);
    VecX vp = v, vm = v;
    vp(c) += h;
    vm(c) -= h;
    dv.col(c) = (g(q, vp) - g(q, vm)) / (2 * h);
  }
}

// springs and dampers on some 1-DOF joints, and a torque
Inputs random_inputs(Rng& rng, const Model& m) {
  Inputs in;
  for (int i = 0; i < m.nbodies; ++i) {
    if (m.nv_i[i] != 1 || rng.uniform(0, 1) < 0.5) continue;
    in.springs.push_back({m.joint_names[i], m.idx_v[i], m.idx_q[i], rng.uniform(1, 50), rng.uniform()});
    in.dampers.push_back({m.joint_names[i], m.idx_v[i], rng.uniform(0.1, 5)});
    in.torques.push_back({m.joint_names[i], m.idx_v[i], rng.uniform()});
  }
  return in;
}

class Derivatives : public ::testing::TestWithParam<Case> {};

TEST_P(Derivatives, InverseDynamicsAgainstCentralDifferences) {
  const Case& c = GetParam();
  for (int seed = 0; seed < 3; ++seed) {
    Rng rng(101 * seed + 7 * c.options.n);
    const Model model = random_model(rng, c.options);
    Data data(model), work(model);
    DerivativeData dd(model);
    const VecX q = random_q(rng, model), v = random_v(rng, model, 2.0), qdd = random_v(rng, model, 3.0);
    update_kinematics(model, data, q);
    inverse_dynamics_derivatives(model, data, v, qdd, dd);
    // the world-frame sweep gives the τ of the note's sweeps
    EXPECT_TRUE(near_rel(dd.tau, tau_at(model, work, q, v, qdd), 1e-11)) << c.name;
    MatX dq, dv;
    central(model, q, v, [&](const VecX& qq, const VecX& vv) { return tau_at(model, work, qq, vv, qdd); }, dq, dv);
    EXPECT_TRUE(near_rel(dd.dtau_dq, dq, 1e-7)) << c.name << " seed " << seed << ": ∂τ/∂q";
    EXPECT_TRUE(near_rel(dd.dtau_dv, dv, 1e-7)) << c.name << " seed " << seed << ": ∂τ/∂v";
    // the derivatives are not trivially small: the comparison means something
    EXPECT_GT(dq.cwiseAbs().maxCoeff(), 1e-2);
  }
}

// a seeded random tree at a random state (q, v, q̈), with its inverse-dynamics derivatives as
// matrices (full) and the sweeps the O(N) products start from (swept): what the product tests compare
struct SweptState {
  Model model;
  Data data;
  DerivativeData full, swept;
  VecX q, v, qdd;
  SweptState(Rng& rng, const TreeOptions& o)
      : model(random_model(rng, o)), data(model), full(model), swept(model), q(random_q(rng, model)),
        v(random_v(rng, model, 2.0)), qdd(random_v(rng, model, 3.0)) {
    update_kinematics(model, data, q);
    inverse_dynamics_derivatives(model, data, v, qdd, full);
    inverse_dynamics_derivative_sweeps(model, data, v, qdd, swept);
  }
};

// the O(N) vector products against the O(N·depth) matrices they leave out (and so, through the test
// above, against central differences), on every joint type
TEST_P(Derivatives, TransposeTimesVectorEqualsTheMatrices) {
  const Case& c = GetParam();
  for (int seed = 0; seed < 3; ++seed) {
    Rng rng(103 * seed + 5 * c.options.n);
    SweptState s(rng, c.options);
    const Model& model = s.model;
    VecX gq(model.nv), gv(model.nv);
    for (int k = 0; k < 2; ++k) {  // two vectors at one state share the sweeps
      const VecX m = random_v(rng, model);
      inverse_dynamics_derivatives_transpose_times(model, s.swept, m, gq, gv);
      EXPECT_TRUE(near_rel(gq, s.full.dtau_dq.transpose() * m, 1e-12)) << c.name << " seed " << seed << ": (∂τ/∂q)ᵀμ";
      EXPECT_TRUE(near_rel(gv, s.full.dtau_dv.transpose() * m, 1e-12)) << c.name << " seed " << seed << ": (∂τ/∂v)ᵀμ";
    }
    EXPECT_TRUE(near_rel(s.swept.tau, s.full.tau, 1e-14)) << c.name;
  }
}

// the products with many directions at once against the matrices: 19 columns (16 rows, then 3 in
// four rows, zero-padded), 10 (twelve rows) and one (one row)
TEST_P(Derivatives, TimesDirectionsEqualsTheMatrices) {
  const Case& c = GetParam();
  for (int seed = 0; seed < 3; ++seed) {
    Rng rng(107 * seed + 7 * c.options.n);
    SweptState s(rng, c.options);
    const Model& model = s.model;
    for (const int k : {DerivativeData::kDirections + 3, 10, 1}) {
      MatX xq(model.nv, k), xv(model.nv, k), out(model.nv, k);
      for (int j = 0; j < k; ++j) xq.col(j) = random_v(rng, model), xv.col(j) = random_v(rng, model);
      inverse_dynamics_derivatives_times(model, s.swept, xq, xv, out);
      const MatX want = s.full.dtau_dq * xq + s.full.dtau_dv * xv;
      EXPECT_TRUE(near_rel(out, want, 1e-12)) << c.name << " seed " << seed << ": ∂τ/∂q xq + ∂τ/∂v xv, " << k << " columns";
      EXPECT_GT(want.cwiseAbs().maxCoeff(), 1e-2);
    }
  }
}

TEST_P(Derivatives, ForwardDynamicsAgainstCentralDifferencesWithInputs) {
  const Case& c = GetParam();
  for (int seed = 0; seed < 3; ++seed) {
    Rng rng(211 * seed + 3 * c.options.n);
    const Model model = random_model(rng, c.options);
    const Inputs in = random_inputs(rng, model);
    Data data(model), work(model);
    DerivativeData dd(model);
    const VecX q = random_q(rng, model), v = random_v(rng, model, 2.0), tau0 = random_v(rng, model, 3.0);
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
    VecX tau(model.nv);
    in.evaluate(0.0, q, v, tau);
    tau += tau0;
    forward_dynamics_derivatives(model, data, v, tau, dd, &in, true);
    EXPECT_TRUE(near_rel(data.qdd, qdd_at(model, work, in, q, v, tau0), 1e-9));
    MatX dq, dv;
    central(model, q, v, [&](const VecX& qq, const VecX& vv) { return qdd_at(model, work, in, qq, vv, tau0); }, dq, dv);
    // q̈ is 𝓜⁻¹ times forces: its error scales with 𝓜's conditioning
    update_kinematics(model, work, q);
    mass_matrix(model, work);
    const Eigen::JacobiSVD<MatX> svd(work.M);
    const double cond = svd.singularValues()(0) / svd.singularValues().tail<1>()(0);
    const double tol = std::max(1e-7, 1e-13 * cond);
    EXPECT_TRUE(near_rel(dd.dqdd_dq, dq, tol)) << c.name << " seed " << seed << ": ∂q̈/∂q, cond " << cond;
    EXPECT_TRUE(near_rel(dd.dqdd_dv, dv, tol)) << c.name << " seed " << seed << ": ∂q̈/∂v, cond " << cond;
    // ∂q̈/∂τ by differences of τ
    MatX dt(model.nv, model.nv);
    for (int k = 0; k < model.nv; ++k) {
      VecX tp = tau0, tm = tau0;
      tp(k) += 1e-4;
      tm(k) -= 1e-4;
      dt.col(k) = (qdd_at(model, work, in, q, v, tp) - qdd_at(model, work, in, q, v, tm)) / 2e-4;
    }
    EXPECT_TRUE(near_rel(dd.Minv, dt, tol)) << c.name << ": ∂q̈/∂τ";
  }
}

// ∂q̈/∂x = −𝓜⁻¹ ∂τ/∂x at fixed q̈, with 𝓜 from the note's literal procedure and a dense LU
TEST_P(Derivatives, ForwardIsMinusInverseMassTimesInverse) {
  const Case& c = GetParam();
  Rng rng(5 + c.options.n);
  const Model model = random_model(rng, c.options);
  Data data(model);
  DerivativeData dd(model), id(model);
  const VecX q = random_q(rng, model), v = random_v(rng, model, 2.0), tau = random_v(rng, model, 3.0);
  update_kinematics(model, data, q);
  update_velocities(model, data, v);
  forward_dynamics_derivatives(model, data, v, tau, dd, nullptr, true);
  MatX M;
  mass_matrix_literal(model, data, M);
  const Eigen::PartialPivLU<MatX> lu(M);
  forward_dynamics(model, data, tau, FdMethod::Dense);
  inverse_dynamics_derivatives(model, data, v, data.qdd, id);
  EXPECT_TRUE(near_rel(dd.dqdd_dq, -lu.solve(id.dtau_dq), 1e-9)) << c.name;
  EXPECT_TRUE(near_rel(dd.dqdd_dv, -lu.solve(id.dtau_dv), 1e-9)) << c.name;
  EXPECT_TRUE(near_rel(dd.Minv, lu.inverse(), 1e-9)) << c.name;
}

INSTANTIATE_TEST_SUITE_P(RandomTrees, Derivatives, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

// The note's Example 1, a pendulum on a cart: bob at (x + L sin θ, −L cos θ), gravity −g e_y.
//   τ_x = (m1 + m2) ẍ + m2 L cos θ θ̈ − m2 L sin θ θ̇²
//   τ_θ = m2 L cos θ ẍ + (I + m2 L²) θ̈ + m2 g L sin θ
TEST(DerivativesClosedForm, PendulumOnCart) {
  const double m1 = 2.0, m2 = 0.7, L = 0.9, I = 0.03, g = 9.81;
  std::vector<BodySpec> specs(2);
  specs[0].name = "cart";
  specs[0].joint = JointType::Prismatic;
  specs[0].axis = Vec3::UnitX();
  specs[0].mass = m1;
  specs[0].inertia = Vec3(0.1, 0.1, 0.1).asDiagonal();
  specs[1].name = "pole";
  specs[1].parent = 0;
  specs[1].axis = Vec3::UnitZ();
  specs[1].mass = m2;
  specs[1].com = Vec3(0, -L, 0);
  specs[1].inertia = Vec3(0.02, 0.02, I).asDiagonal();
  const Model model = Model::build(specs, Vec3(0, -g, 0));
  Data data(model);
  DerivativeData dd(model);
  for (const double th : {0.0, 0.4, 2.5, -1.2}) {
    const VecX q = (VecX(2) << 0.3, th).finished(), v = (VecX(2) << -0.5, 1.7).finished();
    const VecX qdd = (VecX(2) << 0.8, -2.1).finished();
    update_kinematics(model, data, q);
    inverse_dynamics_derivatives(model, data, v, qdd, dd);
    const double s = std::sin(th), co = std::cos(th), xdd = qdd(0), thd = v(1), thdd = qdd(1);
    MatX dq(2, 2), dv(2, 2);
    dq << 0, -m2 * L * s * thdd - m2 * L * co * thd * thd, 0, -m2 * L * s * xdd + m2 * g * L * co;
    dv << 0, -2 * m2 * L * s * thd, 0, 0;
    EXPECT_TRUE(near_rel(dd.dtau_dq, dq, 1e-12)) << th;
    EXPECT_TRUE(near_rel(dd.dtau_dv, dv, 1e-12)) << th;
    // forward: ∂q̈/∂θ of the 2×2 system, by the quotient rule on 𝓜⁻¹ (τ − bias) with τ = 0
    update_velocities(model, data, v);
    forward_dynamics_derivatives(model, data, v, VecX::Zero(2), dd);
    Eigen::Matrix2d M, dM;
    M << m1 + m2, m2 * L * co, m2 * L * co, I + m2 * L * L;
    dM << 0, -m2 * L * s, -m2 * L * s, 0;
    const Eigen::Vector2d bias(-m2 * L * s * thd * thd, m2 * g * L * s), dbias(-m2 * L * co * thd * thd, m2 * g * L * co);
    const Eigen::Vector2d a = M.inverse() * (-bias);
    const Eigen::Vector2d da = M.inverse() * (-dbias - dM * a);
    EXPECT_TRUE(near_rel(dd.dqdd_dq.col(1), da, 1e-12)) << th;
    EXPECT_TRUE(near_rel(dd.dqdd_dq.col(0), Eigen::Vector2d::Zero(), 1e-12)) << th;
  }
}

TEST(DerivativesErrors, WrongSizesAreRefused) {
  Rng rng(1);
  const Model model = random_model(rng, {.n = 4});
  const Model other = random_model(rng, {.n = 5});
  Data data(model);
  DerivativeData dd(model), wrong(other);
  update_kinematics(model, data, random_q(rng, model));
  EXPECT_THROW(inverse_dynamics_derivatives(model, data, VecX::Zero(3), VecX::Zero(4), dd), Error);
  EXPECT_THROW(inverse_dynamics_derivatives(model, data, VecX::Zero(4), VecX::Zero(4), wrong), Error);
}

}  // namespace
