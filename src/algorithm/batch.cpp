#include "soadyn/algorithm/batch.hpp"

#include "soadyn/algorithm/kinematics.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <string>
#include <thread>

namespace soadyn::batch {

int resolve_threads(int threads) {
  if (threads > 0) return threads;
  return std::max(1, int(std::thread::hardware_concurrency()));
}

Pool::Pool(const Model& model, int threads) : model_(model), threads_(resolve_threads(threads)) {
  workers_.resize(size_t(threads_));
}

Pool::Worker& Pool::worker(int w) {
  auto& slot = workers_[size_t(w)];
  if (!slot) slot = std::make_unique<Worker>(model_);
  return *slot;
}

void Pool::run(long K, const std::function<void(Worker&, long, long)>& f) {
  if (K <= 0) return;
  const int n = int(std::min<long>(threads_, K));
  if (n == 1) {
    f(worker(0), 0, K);
    return;
  }
  // the first states here, timed: is the rest worth starting threads for?  A few states only (1, 2,
  // 4, … until kProbeSeconds), not a whole chunk: what runs before the threads start runs on one
  // thread (a first chunk of K/16 held 2 threads to 16/8.5 = 1.88× at best)
  Worker& first = worker(0);
  const auto t0 = std::chrono::steady_clock::now();
  long probed = 0;
  double elapsed = 0;
  for (long m = 1; probed < K && elapsed < kProbeSeconds; m *= 2) {
    const long end = std::min(K, probed + m);
    f(first, probed, end);
    probed = end;
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  if (double(K - probed) * elapsed / double(probed) < worth_a_thread) {
    f(first, probed, K);
    return;
  }
  for (int t = 1; t < n; ++t) worker(t);  // sized here, before the threads start
  // chunks handed out in order from one counter, guided: each a 1/(4n) share of the states not yet
  // handed out, and at least ~kProbeSeconds of work: few grabs while much is left, a thread that
  // stalls (the machine is shared) holds at most 1/(4n) of the rest, and the last chunks are
  // small, so no thread idles long at the end (chunks of a fixed K/(8n) left up to one, 1/16 of
  // the work on 2 threads, to a single thread); which thread takes a chunk changes no result
  const long min_chunk = std::max(1L, long(double(probed) * kProbeSeconds / std::max(elapsed, 1e-9)));
  std::atomic<long> next{probed};
  auto grab = [&](long& begin, long& end) {
    long b = next.load(std::memory_order_relaxed);
    for (;;) {
      if (b >= K) return false;
      const long e = std::min(K, b + std::max(min_chunk, (K - b) / (4L * n)));
      if (next.compare_exchange_weak(b, e, std::memory_order_relaxed)) {
        begin = b, end = e;
        return true;
      }
    }
  };
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&](Worker& w) {
    try {
      for (long begin, end; !failed.load(std::memory_order_relaxed) && grab(begin, end);) f(w, begin, end);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      failed = true;
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(size_t(n - 1));
  for (int t = 1; t < n; ++t) threads.emplace_back(work, std::ref(*workers_[size_t(t)]));
  work(first);
  for (auto& t : threads) t.join();
  if (error) std::rethrow_exception(error);
}

namespace {

std::string shape(Eigen::Index rows, Eigen::Index cols) { return std::to_string(rows) + "×" + std::to_string(cols); }

// always-on: an n×K argument (K taken from Q) is what it should be, before any state is read
void check(const char* where, const char* what, Eigen::Index rows, Eigen::Index cols, Eigen::Index n, Eigen::Index K) {
  if (rows == n && cols == K) return;
  throw Error(std::string("batch::") + where + ": " + what + ": expected " + shape(n, K) + " (" + std::to_string(n) +
              " rows, one column per state), got " + shape(rows, cols));
}

// state k into the worker's q (and v)
void load(Pool::Worker& w, const In& Q, long k) { w.q = Q.col(k); }
void load(Pool::Worker& w, const In& Q, const In& V, long k) {
  w.q = Q.col(k);
  w.v = V.col(k);
}

}  // namespace

void forward_dynamics(Pool& pool, In Q, In V, In TAU, Out QDD, FdMethod method) {
  const Model& m = pool.model();
  const Eigen::Index K = Q.cols();
  check("forward_dynamics", "Q", Q.rows(), K, m.nq, K);
  check("forward_dynamics", "V", V.rows(), V.cols(), m.nv, K);
  check("forward_dynamics", "TAU", TAU.rows(), TAU.cols(), m.nv, K);
  check("forward_dynamics", "QDD", QDD.rows(), QDD.cols(), m.nv, K);
  pool.run(K, [&](Pool::Worker& w, long begin, long end) {
    for (long k = begin; k < end; ++k) {
      load(w, Q, V, k);
      w.x = TAU.col(k);
      update_kinematics(m, w.data, w.q);
      update_velocities(m, w.data, w.v);
      soadyn::forward_dynamics(m, w.data, w.x, method);
      QDD.col(k) = w.data.qdd;
    }
  });
}

void mass_matrix(Pool& pool, In Q, Out M) {
  const Model& m = pool.model();
  const Eigen::Index K = Q.cols();
  check("mass_matrix", "Q", Q.rows(), K, m.nq, K);
  check("mass_matrix", "M", M.rows(), M.cols(), m.nv, m.nv * K);
  pool.run(K, [&](Pool::Worker& w, long begin, long end) {
    for (long k = begin; k < end; ++k) {
      load(w, Q, k);
      soadyn::mass_matrix(m, w.data, w.q);
      M.middleCols(k * m.nv, m.nv) = w.data.M;
    }
  });
}

void bias_forces(Pool& pool, In Q, In V, Out B) {
  const Model& m = pool.model();
  const Eigen::Index K = Q.cols();
  check("bias_forces", "Q", Q.rows(), K, m.nq, K);
  check("bias_forces", "V", V.rows(), V.cols(), m.nv, K);
  check("bias_forces", "B", B.rows(), B.cols(), m.nv, K);
  pool.run(K, [&](Pool::Worker& w, long begin, long end) {
    for (long k = begin; k < end; ++k) {
      load(w, Q, V, k);
      bias_forces(m, w.data, w.q, w.v);
      B.col(k) = w.data.bias;
    }
  });
}

void inverse_dynamics(Pool& pool, In Q, In V, In QDD, Out TAU) {
  const Model& m = pool.model();
  const Eigen::Index K = Q.cols();
  check("inverse_dynamics", "Q", Q.rows(), K, m.nq, K);
  check("inverse_dynamics", "V", V.rows(), V.cols(), m.nv, K);
  check("inverse_dynamics", "QDD", QDD.rows(), QDD.cols(), m.nv, K);
  check("inverse_dynamics", "TAU", TAU.rows(), TAU.cols(), m.nv, K);
  pool.run(K, [&](Pool::Worker& w, long begin, long end) {
    for (long k = begin; k < end; ++k) {
      load(w, Q, V, k);
      w.x = QDD.col(k);
      update_kinematics(m, w.data, w.q);
      update_velocities(m, w.data, w.v);
      soadyn::inverse_dynamics(m, w.data, w.x);
      TAU.col(k) = w.data.tau;
    }
  });
}

void inverse_dynamics_derivatives(Pool& pool, In Q, In V, In QDD, Out DQ, Out DV) {
  const Model& m = pool.model();
  const Eigen::Index K = Q.cols();
  const char* where = "inverse_dynamics_derivatives";
  check(where, "Q", Q.rows(), K, m.nq, K);
  check(where, "V", V.rows(), V.cols(), m.nv, K);
  check(where, "QDD", QDD.rows(), QDD.cols(), m.nv, K);
  check(where, "DQ", DQ.rows(), DQ.cols(), m.nv, m.nv * K);
  check(where, "DV", DV.rows(), DV.cols(), m.nv, m.nv * K);
  pool.run(K, [&](Pool::Worker& w, long begin, long end) {
    if (!w.dd) w.dd.emplace(m);
    for (long k = begin; k < end; ++k) {
      load(w, Q, V, k);
      w.x = QDD.col(k);
      update_kinematics(m, w.data, w.q);
      soadyn::inverse_dynamics_derivatives(m, w.data, w.v, w.x, *w.dd);
      DQ.middleCols(k * m.nv, m.nv) = w.dd->dtau_dq;
      DV.middleCols(k * m.nv, m.nv) = w.dd->dtau_dv;
    }
  });
}

void forward_dynamics_derivatives(Pool& pool, In Q, In V, In TAU, Out DQ, Out DV, Out* MINV, Out* QDD) {
  const Model& m = pool.model();
  const Eigen::Index K = Q.cols();
  const char* where = "forward_dynamics_derivatives";
  check(where, "Q", Q.rows(), K, m.nq, K);
  check(where, "V", V.rows(), V.cols(), m.nv, K);
  check(where, "TAU", TAU.rows(), TAU.cols(), m.nv, K);
  check(where, "DQ", DQ.rows(), DQ.cols(), m.nv, m.nv * K);
  check(where, "DV", DV.rows(), DV.cols(), m.nv, m.nv * K);
  if (MINV) check(where, "MINV", MINV->rows(), MINV->cols(), m.nv, m.nv * K);
  if (QDD) check(where, "QDD", QDD->rows(), QDD->cols(), m.nv, K);
  pool.run(K, [&](Pool::Worker& w, long begin, long end) {
    if (!w.dd) w.dd.emplace(m);
    for (long k = begin; k < end; ++k) {
      load(w, Q, V, k);
      w.x = TAU.col(k);
      update_kinematics(m, w.data, w.q);
      update_velocities(m, w.data, w.v);
      soadyn::forward_dynamics_derivatives(m, w.data, w.v, w.x, *w.dd, nullptr, MINV != nullptr);
      DQ.middleCols(k * m.nv, m.nv) = w.dd->dqdd_dq;
      DV.middleCols(k * m.nv, m.nv) = w.dd->dqdd_dv;
      if (MINV) MINV->middleCols(k * m.nv, m.nv) = w.dd->Minv;
      if (QDD) QDD->col(k) = w.data.qdd;
    }
  });
}

void frame_jacobian(Pool& pool, In Q, int frame, Reference reference, Out J) {
  const Model& m = pool.model();
  const Eigen::Index K = Q.cols();
  check("frame_jacobian", "Q", Q.rows(), K, m.nq, K);
  check("frame_jacobian", "J", J.rows(), J.cols(), 6, m.nv * K);
  if (frame < 0 || frame >= int(m.frame_names.size()))
    throw Error("batch::frame_jacobian: frame: expected an index 0.." + std::to_string(int(m.frame_names.size()) - 1) +
                ", got " + std::to_string(frame));
  pool.run(K, [&](Pool::Worker& w, long begin, long end) {
    for (long k = begin; k < end; ++k) {
      load(w, Q, k);
      update_kinematics(m, w.data, w.q);
      soadyn::frame_jacobian(m, w.data, frame, reference, w.J);
      J.middleCols(k * m.nv, m.nv) = w.J;
    }
  });
}

// the same with a Pool for the call
void forward_dynamics(const Model& model, In Q, In V, In TAU, Out QDD, int threads, FdMethod method) {
  Pool pool(model, threads);
  forward_dynamics(pool, Q, V, TAU, QDD, method);
}
void mass_matrix(const Model& model, In Q, Out M, int threads) {
  Pool pool(model, threads);
  mass_matrix(pool, Q, M);
}
void bias_forces(const Model& model, In Q, In V, Out B, int threads) {
  Pool pool(model, threads);
  bias_forces(pool, Q, V, B);
}
void inverse_dynamics(const Model& model, In Q, In V, In QDD, Out TAU, int threads) {
  Pool pool(model, threads);
  inverse_dynamics(pool, Q, V, QDD, TAU);
}
void inverse_dynamics_derivatives(const Model& model, In Q, In V, In QDD, Out DQ, Out DV, int threads) {
  Pool pool(model, threads);
  inverse_dynamics_derivatives(pool, Q, V, QDD, DQ, DV);
}
void forward_dynamics_derivatives(const Model& model, In Q, In V, In TAU, Out DQ, Out DV, int threads, Out* MINV,
                                  Out* QDD) {
  Pool pool(model, threads);
  forward_dynamics_derivatives(pool, Q, V, TAU, DQ, DV, MINV, QDD);
}

void frame_jacobian(const Model& model, In Q, int frame, Reference reference, Out J, int threads) {
  Pool pool(model, threads);
  frame_jacobian(pool, Q, frame, reference, J);
}

}  // namespace soadyn::batch
