// Many states at once: the algorithms of algorithms.hpp and derivatives.hpp over K states, split
// across threads, each thread with its own Data kept in a Pool.
//
// Layout.  A batch of K vectors of size n is an n×K column-major matrix, column k = state k: the
// memory of a row-major (K, n) numpy array, so Python passes its arrays without a copy.  A batch of
// nv×nv results (𝓜, the derivatives) is an nv×(nv·K) matrix, block k (columns k·nv … k·nv + nv − 1)
// the matrix of state k: in numpy, shape (K, nv, nv) with strides (nv², 1, nv)·8.
//
// Determinism.  Every state is computed alone, by the same single-state call (update_kinematics,
// update_velocities, then the algorithm) on the Data of whichever thread takes it, and no algorithm
// reads what a Data held before its stages filled it again: the results are bitwise those of the
// loop over states, whatever the thread count (test_batch).
//
// No allocation per state: the Pool sizes every per-thread array once, when a thread first needs it
// (the derivatives' workspace on the first derivative call); a call allocates only the threads it
// starts.  A thread costs ~0.1 ms to start and join: the calling thread times its first states and
// starts the others only when the rest of the work is worth it (kWorthAThread), so small batches
// run on the calling thread alone.
#pragma once

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/multibody/data.hpp"
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/multibody/model.hpp"

#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace soadyn::batch {

using In = Eigen::Ref<const MatX>;  // n×K, column k = state k
using Out = Eigen::Ref<MatX>;

// threads ≤ 0: one per hardware thread (std::thread::hardware_concurrency)
int resolve_threads(int threads);

// work left (seconds on one thread) below which Pool::run starts no other thread: several thread
// starts, so that a second thread at least halves what is left after paying for its start
inline constexpr double kWorthAThread = 5e-4;
// how long Pool::run times its first states for (seconds): enough states for a rate, few enough that
// the one thread working meanwhile costs the others little
inline constexpr double kProbeSeconds = 2e-5;

// One Data (and, on demand, one DerivativeData) per thread, sized once from the model.
class Pool {
 public:
  Pool(const Model& model, int threads);
  const Model& model() const { return model_; }
  int threads() const { return threads_; }
  // run's threshold for starting threads (seconds of work left); 0 starts every thread (tests)
  double worth_a_thread = kWorthAThread;

  struct Worker {
    explicit Worker(const Model& m) : data(m), q(m.nq), v(m.nv), x(m.nv), J(6, m.nv) {}
    Data data;
    std::optional<DerivativeData> dd;  // made by the first derivative call on this worker
    VecX q, v, x;                      // state k copied here (the algorithms take VecX)
    MatX J;                            // 6×nv: a frame Jacobian
  };

  // f(worker, begin, end) over [0, K) in chunks, each chunk on one thread with that thread's
  // worker; the calling thread takes part and times its first states (kProbeSeconds): the other
  // threads start only when the states left would take it longer than kWorthAThread.  An exception in any chunk is rethrown here after
  // every thread has stopped (the remaining chunks are skipped).
  void run(long K, const std::function<void(Worker&, long begin, long end)>& f);

 private:
  Worker& worker(int w);  // made on first use

  const Model& model_;
  int threads_;
  std::vector<std::unique_ptr<Worker>> workers_;
};

// Each call checks the shapes (rows nq or nv, K columns alike; soadyn::Error naming the argument,
// expected and got) before any work.  The `threads` overloads make a Pool for the call.

// q̈ = 𝓜⁻¹ (τ − bias) of each state: Q nq×K, V and TAU nv×K → QDD nv×K
void forward_dynamics(Pool& pool, In Q, In V, In TAU, Out QDD, FdMethod method = FdMethod::ArticulatedBody);
void forward_dynamics(const Model& model, In Q, In V, In TAU, Out QDD, int threads,
                      FdMethod method = FdMethod::ArticulatedBody);

// 𝓜(q) of each state (mass_matrix(model, data, q), body axes): Q nq×K → M nv×(nv·K)
void mass_matrix(Pool& pool, In Q, Out M);
void mass_matrix(const Model& model, In Q, Out M, int threads);

// bias(q, q̇) (bias_forces(model, data, q, v)): Q nq×K, V nv×K → B nv×K
void bias_forces(Pool& pool, In Q, In V, Out B);
void bias_forces(const Model& model, In Q, In V, Out B, int threads);
// the old name, kept one release
[[deprecated("use batch::bias_forces")]] inline void bias(Pool& pool, In Q, In V, Out B) { bias_forces(pool, Q, V, B); }
[[deprecated("use batch::bias_forces")]] inline void bias(const Model& model, In Q, In V, Out B, int threads) {
  bias_forces(model, Q, V, B, threads);
}

// τ = 𝓜 q̈ + bias: Q nq×K, V and QDD nv×K → TAU nv×K
void inverse_dynamics(Pool& pool, In Q, In V, In QDD, Out TAU);
void inverse_dynamics(const Model& model, In Q, In V, In QDD, Out TAU, int threads);

// ∂τ/∂q, ∂τ/∂v of inverse dynamics (derivatives.hpp): → DQ, DV nv×(nv·K)
void inverse_dynamics_derivatives(Pool& pool, In Q, In V, In QDD, Out DQ, Out DV);
void inverse_dynamics_derivatives(const Model& model, In Q, In V, In QDD, Out DQ, Out DV, int threads);

// ∂q̈/∂q, ∂q̈/∂v of forward dynamics, τ held fixed: → DQ, DV nv×(nv·K); with MINV (nv×(nv·K), not
// null) also ∂q̈/∂τ = 𝓜⁻¹, and with QDD (nv×K, not null) q̈ itself
void forward_dynamics_derivatives(Pool& pool, In Q, In V, In TAU, Out DQ, Out DV, Out* MINV = nullptr,
                                  Out* QDD = nullptr);
void forward_dynamics_derivatives(const Model& model, In Q, In V, In TAU, Out DQ, Out DV, int threads,
                                  Out* MINV = nullptr, Out* QDD = nullptr);

// the Jacobian of frame `frame` (an index of Model::frame_names) in `reference` (frames.hpp) at
// each state: Q nq×K → J 6×(nv·K), block k the 6×nv J of state k
void frame_jacobian(Pool& pool, In Q, int frame, Reference reference, Out J);
void frame_jacobian(const Model& model, In Q, int frame, Reference reference, Out J, int threads);

}  // namespace soadyn::batch
