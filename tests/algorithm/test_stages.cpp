// The stage rule (data.hpp: Data::stages): a call whose input stage does not hold is refused with
// the missing update named (a fresh Data; [vel] after update_kinematics at a new q; [kin] after the
// frames alone), never answered with NaN or another state's numbers; and the one-call entry points
// (forward_dynamics(q, v, τ), inverse_dynamics(q, v, q̈), mass_matrix(q), bias_forces(q, v)) equal the
// staged pipeline on random trees with free roots, ball, planar and prismatic joints.
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/frames.hpp"

#include "test_util.hpp"

using namespace soadyn;
using namespace soadyn::test;
using ::testing::HasSubstr;

namespace {

Model tree(std::uint64_t seed, bool free_root) {
  Rng rng(seed);
  return random_model(rng, {.n = 12, .branching = 0.5, .prismatic = 0.2, .ball = 0.15, .planar = 0.1, .free_root = free_root});
}

}  // namespace

// a fresh Data holds no stage: every reader of [kin] or [vel] refuses, naming what to call
TEST(Stages, FreshDataIsRefusedByEveryReader) {
  const Model m = tree(1, true);
  Data d(m);
  Rng rng(2);
  const VecX v = random_v(rng, m), tau = random_v(rng, m);
  MatX M, J, Minv;
  DerivativeData dd(m);
  const std::vector<std::pair<const char*, std::function<void()>>> calls = {
      {"forward_dynamics", [&] { forward_dynamics(m, d, tau, FdMethod::ArticulatedBody); }},
      {"forward_dynamics", [&] { forward_dynamics(m, d, tau, FdMethod::Dense); }},
      {"forward_dynamics", [&] { forward_dynamics(m, d, tau, FdMethod::Sparse); }},
      {"inverse_dynamics", [&] { inverse_dynamics(m, d, tau); }},
      {"bias_forces", [&] { bias_forces(m, d); }},
      {"mass_matrix", [&] { mass_matrix(m, d); }},
      {"mass_matrix_literal", [&] { mass_matrix_literal(m, d, M); }},
      {"minverse", [&] { minverse(m, d, Minv); }},
      {"jacobian", [&] { jacobian(m, d, J); }},
      {"update_velocities", [&] { update_velocities(m, d, v); }},
      {"kinetic_energy", [&] { (void)kinetic_energy(m, d); }},
      {"potential_energy", [&] { (void)potential_energy(m, d); }},
      {"momentum", [&] { (void)momentum(m, d); }},
      {"inverse_dynamics_derivatives", [&] { inverse_dynamics_derivatives(m, d, v, tau, dd); }},
      {"forward_dynamics_derivatives", [&] { forward_dynamics_derivatives(m, d, v, tau, dd, nullptr, true); }},
  };
  for (const auto& [name, call] : calls) {
    const std::string msg = message_of(call);
    EXPECT_THAT(msg, HasSubstr(std::string(name) + ": needs [kin]")) << name;
    EXPECT_THAT(msg, HasSubstr("update_kinematics(model, data, q)")) << name;
  }
  EXPECT_TRUE(d.qdd.isZero());  // nothing was computed into the results
}

// update_kinematics at a new q clears [vel]: the dynamics refuse until update_velocities, and the
// q̈ they then give is the one of the new state (not the stale mix the old v would give)
TEST(Stages, StaleVelocitiesAreRefused) {
  for (const bool free_root : {false, true}) {
    const Model m = tree(3, free_root);
    Rng rng(4);
    const VecX q1 = random_q(rng, m), q2 = random_q(rng, m), v = random_v(rng, m), tau = random_v(rng, m);
    Data d(m);
    update_kinematics(m, d, q1);
    update_velocities(m, d, v);
    forward_dynamics(m, d, tau, FdMethod::ArticulatedBody);  // both stages hold
    update_kinematics(m, d, q2);
    mass_matrix(m, d);  // [kin] alone is enough for 𝓜
    for (const FdMethod method : {FdMethod::ArticulatedBody, FdMethod::Dense, FdMethod::Sparse}) {
      const std::string msg = message_of([&] { forward_dynamics(m, d, tau, method); });
      EXPECT_THAT(msg, HasSubstr("forward_dynamics: needs [vel]"));
      EXPECT_THAT(msg, HasSubstr("update_velocities(model, data, v)"));
    }
    EXPECT_THAT(message_of([&] { inverse_dynamics(m, d, tau); }), HasSubstr("inverse_dynamics: needs [vel]"));
    EXPECT_THAT(message_of([&] { bias_forces(m, d); }), HasSubstr("bias_forces: needs [vel]"));
    EXPECT_THAT(message_of([&] { (void)kinetic_energy(m, d); }), HasSubstr("kinetic_energy: needs [vel]"));
    update_velocities(m, d, v);
    forward_dynamics(m, d, tau, FdMethod::ArticulatedBody);
    Data fresh(m);
    forward_dynamics(m, fresh, q2, v, tau);
    EXPECT_TRUE(near_rel(d.qdd, fresh.qdd, 1e-12)) << "free root " << free_root;
  }
}

// the frames alone (update_frames, update_frames_to) leave s, r and M_i of another q: [kin] and
// [vel] no longer hold
TEST(Stages, FramesAloneClearKinematics) {
  const Model m = tree(5, false);
  Rng rng(6);
  const VecX q = random_q(rng, m), v = random_v(rng, m);
  Data d(m);
  update_kinematics(m, d, q);
  update_velocities(m, d, v);
  update_frames(m, d, random_q(rng, m));
  EXPECT_THAT(message_of([&] { mass_matrix(m, d); }), HasSubstr("mass_matrix: needs [kin]"));
  update_kinematics(m, d, q);
  update_velocities(m, d, v);
  update_frames_to(m, d, random_q(rng, m), m.nbodies - 1);
  EXPECT_THAT(message_of([&] { (void)potential_energy(m, d); }), HasSubstr("potential_energy: needs [kin]"));
  update_kinematics(m, d, q);
  update_frames_to(m, d, q, -1);  // the world: nothing changed, [kin] still holds
  EXPECT_EQ(message_of([&] { mass_matrix(m, d); }), "(no error)");
}

// one call from the state equals the staged pipeline, every route, and leaves both stages holding
TEST(Stages, OneCallEqualsStaged) {
  for (std::uint64_t seed = 10; seed < 16; ++seed) {
    const Model m = tree(seed, seed % 2 == 0);
    Rng rng(seed + 100);
    const VecX q = random_q(rng, m), v = random_v(rng, m), tau = random_v(rng, m), qdd = random_v(rng, m);
    Data staged(m), one(m);
    update_kinematics(m, staged, q);
    update_velocities(m, staged, v);
    for (const FdMethod method : {FdMethod::ArticulatedBody, FdMethod::Dense, FdMethod::Sparse}) {
      forward_dynamics(m, staged, tau, method);
      const VecX& got = forward_dynamics(m, one, q, v, tau, method);
      EXPECT_EQ(&got, &one.qdd);
      EXPECT_TRUE(near_rel(got, staged.qdd, 1e-11)) << "seed " << seed << " " << to_string(method);
    }
    inverse_dynamics(m, staged, qdd);
    EXPECT_TRUE(near_rel(inverse_dynamics(m, one, q, v, qdd), staged.tau, 1e-11)) << "seed " << seed;
    // τ(q̈(τ)) = τ through the one-call pair
    Data back(m);
    EXPECT_TRUE(near_rel(inverse_dynamics(m, back, q, v, forward_dynamics(m, one, q, v, tau)), tau, 1e-9));
    mass_matrix(m, staged);
    mass_matrix(m, one, q);
    EXPECT_TRUE(near_rel(one.M, staged.M, 1e-11));
    bias_forces(m, staged);
    bias_forces(m, one, q, v);
    EXPECT_TRUE(near_rel(one.bias, staged.bias, 1e-11));
    EXPECT_EQ(message_of([&] { (void)kinetic_energy(m, one); }), "(no error)");  // [kin], [vel] at (q, v)
    EXPECT_NEAR(kinetic_energy(m, one), kinetic_energy(m, staged), 1e-12 * std::max(1.0, kinetic_energy(m, staged)));
  }
}

// a wrong size is named before any work, and the stages are left as they were
TEST(Stages, OneCallChecksSizesFirst) {
  const Model m = tree(7, false);
  Data d(m);
  const VecX q = VecX::Zero(m.nq), v = VecX::Zero(m.nv), short_tau = VecX::Zero(m.nv - 1);
  EXPECT_THAT(message_of([&] { forward_dynamics(m, d, q, v, short_tau); }), HasSubstr("forward_dynamics: tau: expected"));
  EXPECT_THAT(message_of([&] { inverse_dynamics(m, d, q, short_tau, v); }), HasSubstr("inverse_dynamics: v: expected"));
  EXPECT_FALSE(d.stages.kinematics);
}
