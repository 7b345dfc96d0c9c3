// soadyn::batch: many states at once equal the loop over them, to the last bit, for any thread count.
//
// Exact equality is the claim here, not a shortcut: a batched state is computed by the same
// single-state calls, on the same inputs, as the loop below, only on another thread's Data.  Any
// difference would mean that a result depends on what a Data held before (a stale cache) or on
// which thread ran it, which is exactly what must not happen.  The reference loop runs the states
// in reverse order on one Data, so that a result leaking from one state into the next would show.
#include "soadyn/algorithm/batch.hpp"

#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "test_util.hpp"

#include <atomic>
#include <chrono>
#include <string>
#include <thread>

namespace soadyn {
namespace {

using test::Rng;

struct States {
  MatX Q, V, X;  // nq×K, nv×K, nv×K (τ or q̈)
};

States random_states(Rng& rng, const Model& m, long K) {
  States s{MatX(m.nq, K), MatX(m.nv, K), MatX(m.nv, K)};
  for (long k = 0; k < K; ++k) {
    s.Q.col(k) = test::random_q(rng, m);
    s.V.col(k) = test::random_v(rng, m);
    s.X.col(k) = test::random_v(rng, m, 3.0);
  }
  return s;
}

// a tree with every joint type and a free root: 1 + 12 bodies
Model mixed_model(Rng& rng) {
  test::TreeOptions o;
  o.n = 12;
  o.free_root = true;
  o.prismatic = 0.2;
  o.ball = 0.2;
  o.planar = 0.1;
  o.unit_axis = 0.3;
  return test::random_model(rng, o);
}

constexpr long kStates = 37;  // not a multiple of any thread count tried
const int kThreads[] = {1, 2, 3};

// a pool that starts all its threads however small the batch (Pool::run would keep 37 states of
// these small models on the calling thread)
struct EveryThread : batch::Pool {
  EveryThread(const Model& m, int threads) : batch::Pool(m, threads) { worth_a_thread = 0.0; }
};

TEST(Batch, ForwardDynamicsEqualsLoop) {
  Rng rng(11);
  const Model m = mixed_model(rng);
  const States s = random_states(rng, m, kStates);
  for (const FdMethodInfo& info : fd_methods()) {
    MatX ref(m.nv, kStates);
    Data d(m);
    for (long k = kStates - 1; k >= 0; --k) {
      update_kinematics(m, d, s.Q.col(k));
      update_velocities(m, d, s.V.col(k));
      forward_dynamics(m, d, s.X.col(k), info.method);
      ref.col(k) = d.qdd;
    }
    for (int threads : kThreads) {
      MatX qdd(m.nv, kStates);
      EveryThread pool(m, threads);
      batch::forward_dynamics(pool, s.Q, s.V, s.X, qdd, info.method);
      EXPECT_TRUE(qdd == ref) << info.name << ", " << threads << " threads";
    }
  }
}

TEST(Batch, MassMatrixBiasInverseDynamicsEqualLoop) {
  Rng rng(12);
  const Model m = mixed_model(rng);
  const States s = random_states(rng, m, kStates);
  const int nv = m.nv;
  MatX M_ref(nv, nv * kStates), b_ref(nv, kStates), tau_ref(nv, kStates);
  Data d(m);
  for (long k = kStates - 1; k >= 0; --k) {
    mass_matrix(m, d, VecX(s.Q.col(k)));
    M_ref.middleCols(k * nv, nv) = d.M;
    bias_forces(m, d, s.Q.col(k), s.V.col(k));
    b_ref.col(k) = d.bias;
    update_kinematics(m, d, s.Q.col(k));
    update_velocities(m, d, s.V.col(k));
    inverse_dynamics(m, d, s.X.col(k));
    tau_ref.col(k) = d.tau;
  }
  for (int threads : kThreads) {
    EveryThread pool(m, threads);  // one pool for the three calls: its Data carry over between them
    MatX M(nv, nv * kStates), b(nv, kStates), tau(nv, kStates);
    batch::mass_matrix(pool, s.Q, M);
    batch::bias_forces(pool, s.Q, s.V, b);
    batch::inverse_dynamics(pool, s.Q, s.V, s.X, tau);
    EXPECT_TRUE(M == M_ref) << threads << " threads";
    EXPECT_TRUE(b == b_ref) << threads << " threads";
    EXPECT_TRUE(tau == tau_ref) << threads << " threads";
  }
}

TEST(Batch, DerivativesEqualLoop) {
  Rng rng(13);
  const Model m = mixed_model(rng);
  const States s = random_states(rng, m, kStates);
  const int nv = m.nv;
  MatX idq(nv, nv * kStates), idv(nv, nv * kStates), fdq(nv, nv * kStates), fdv(nv, nv * kStates),
      minv(nv, nv * kStates), qdd(nv, kStates);
  Data d(m);
  DerivativeData dd(m);
  for (long k = kStates - 1; k >= 0; --k) {
    const VecX v = s.V.col(k), x = s.X.col(k);
    update_kinematics(m, d, s.Q.col(k));
    inverse_dynamics_derivatives(m, d, v, x, dd);
    idq.middleCols(k * nv, nv) = dd.dtau_dq;
    idv.middleCols(k * nv, nv) = dd.dtau_dv;
    update_velocities(m, d, v);
    forward_dynamics_derivatives(m, d, v, x, dd, nullptr, true);
    fdq.middleCols(k * nv, nv) = dd.dqdd_dq;
    fdv.middleCols(k * nv, nv) = dd.dqdd_dv;
    minv.middleCols(k * nv, nv) = dd.Minv;
    qdd.col(k) = d.qdd;
  }
  for (int threads : kThreads) {
    EveryThread pool(m, threads);
    MatX a(nv, nv * kStates), b(nv, nv * kStates), c(nv, nv * kStates), e(nv, nv * kStates), f(nv, kStates);
    batch::inverse_dynamics_derivatives(pool, s.Q, s.V, s.X, a, b);
    EXPECT_TRUE(a == idq) << threads << " threads";
    EXPECT_TRUE(b == idv) << threads << " threads";
    Eigen::Ref<MatX> minv_out(e), qdd_out(f);
    batch::forward_dynamics_derivatives(pool, s.Q, s.V, s.X, a, b, &minv_out, &qdd_out);
    EXPECT_TRUE(a == fdq) << threads << " threads";
    EXPECT_TRUE(b == fdv) << threads << " threads";
    EXPECT_TRUE(e == minv) << threads << " threads";
    EXPECT_TRUE(f == qdd) << threads << " threads";
    batch::forward_dynamics_derivatives(pool, s.Q, s.V, s.X, c, b);  // without 𝓜⁻¹: the same ∂q̈/∂q
    EXPECT_TRUE(c == fdq) << threads << " threads";
  }
}

TEST(Batch, FrameJacobianEqualsLoop) {
  Rng rng(19);
  const Model m = mixed_model(rng);
  const States s = random_states(rng, m, kStates);
  const int nv = m.nv, frame = int(m.frame_names.size()) - 1;
  for (const ReferenceInfo& ref : references()) {
    MatX J_ref(6, nv * kStates), J;
    Data d(m);
    for (long k = kStates - 1; k >= 0; --k) {
      update_kinematics(m, d, s.Q.col(k));
      frame_jacobian(m, d, frame, ref.reference, J);
      J_ref.middleCols(k * nv, nv) = J;
    }
    for (int threads : kThreads) {
      EveryThread pool(m, threads);
      MatX out(6, nv * kStates);
      batch::frame_jacobian(pool, s.Q, frame, ref.reference, out);
      EXPECT_TRUE(out == J_ref) << ref.name << ", " << threads << " threads";
    }
  }
  MatX out(6, nv * kStates);
  EXPECT_THROW(batch::frame_jacobian(m, s.Q, int(m.frame_names.size()), Reference::World, out, 1), Error);
}

TEST(Batch, MoreThreadsThanStatesAndNoStates) {
  Rng rng(14);
  const Model m = mixed_model(rng);
  const States s = random_states(rng, m, 2);
  MatX ref(m.nv, 2), qdd(m.nv, 2);
  batch::forward_dynamics(m, s.Q, s.V, s.X, ref, 1);
  EveryThread five(m, 5);
  batch::forward_dynamics(five, s.Q, s.V, s.X, qdd);
  EXPECT_TRUE(qdd == ref);
  MatX none(m.nv, 0);
  batch::forward_dynamics(m, MatX(m.nq, 0), MatX(m.nv, 0), MatX(m.nv, 0), none, 2);
  EXPECT_EQ(none.cols(), 0);
}

TEST(Batch, BadShapesRefusedNamingTheArgument) {
  Rng rng(15);
  const Model m = mixed_model(rng);
  const States s = random_states(rng, m, 4);
  MatX out(m.nv, 4), wide(m.nv, m.nv * 4);
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  using ::testing::HasSubstr;
  const std::string nq = std::to_string(m.nq), nv = std::to_string(m.nv);
  EXPECT_THAT(message([&] { batch::forward_dynamics(m, s.V, s.V, s.X, out, 1); }),
              HasSubstr("batch::forward_dynamics: Q: expected " + nq + "×4"));
  EXPECT_THAT(message([&] { batch::forward_dynamics(m, s.Q, s.V.leftCols(3), s.X, out, 1); }),
              HasSubstr("V: expected " + nv + "×4 (" + nv + " rows, one column per state), got " + nv + "×3"));
  EXPECT_THAT(message([&] { batch::mass_matrix(m, s.Q, out, 1); }),
              HasSubstr("M: expected " + nv + "×" + std::to_string(4 * m.nv)));
  EXPECT_THAT(message([&] { batch::inverse_dynamics_derivatives(m, s.Q, s.V, s.X, wide, out, 2); }),
              HasSubstr("DV: expected"));
}

// a failure inside one thread's chunk reaches the caller, after every thread has stopped
TEST(Batch, ErrorInAThreadIsRethrown) {
  Rng rng(16);
  const Model m = mixed_model(rng);
  EveryThread pool(m, 3);
  EXPECT_THROW(pool.run(100,
                        [](batch::Pool::Worker&, long begin, long end) {
                          if (begin <= 50 && 50 < end) throw Error("state 50");
                        }),
               Error);
}

// the calling thread keeps a small batch: no thread is worth starting for 37 cheap states
TEST(Batch, SmallBatchStaysOnTheCallingThread) {
  Rng rng(18);
  const Model m = mixed_model(rng);
  batch::Pool pool(m, 2);
  std::atomic<int> other{0};
  const auto caller = std::this_thread::get_id();
  pool.run(kStates, [&](batch::Pool::Worker&, long, long) {
    if (std::this_thread::get_id() != caller) ++other;
  });
  EXPECT_EQ(other.load(), 0);
  pool.worth_a_thread = 0.0;
  std::atomic<bool> waited{false};
  pool.run(kStates, [&](batch::Pool::Worker&, long begin, long) {
    if (std::this_thread::get_id() != caller) {
      ++other;
      return;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));  // the probe (from state 0): worth a thread
    // the caller's first share after the probe waits (up to 10 s) for the other thread to take
    // one: on a loaded machine it may start late, and a fixed pause lost that race
    if (begin > 0 && !waited.exchange(true))
      for (int i = 0; i < 100000 && other.load() == 0; ++i) std::this_thread::sleep_for(std::chrono::microseconds(100));
  });
  EXPECT_GT(other.load(), 0);
}

TEST(Batch, NoAllocationPerStateOnOneThread) {
  Rng rng(17);
  const Model m = mixed_model(rng);
  const States s = random_states(rng, m, 8);
  batch::Pool pool(m, 1);
  MatX a(m.nv, m.nv * 8), b(m.nv, m.nv * 8), qdd(m.nv, 8);
  batch::forward_dynamics_derivatives(pool, s.Q, s.V, s.X, a, b);  // the derivatives' workspace, once
  Eigen::internal::set_is_malloc_allowed(false);
  batch::forward_dynamics(pool, s.Q, s.V, s.X, qdd);
  batch::forward_dynamics_derivatives(pool, s.Q, s.V, s.X, a, b);
  Eigen::internal::set_is_malloc_allowed(true);
}

}  // namespace
}  // namespace soadyn
