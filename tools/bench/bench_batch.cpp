// States per second of q̈ and of ∂q̈ (forward_dynamics, forward_dynamics_derivatives without 𝓜⁻¹)
// over K states: the plain C++ loop on one Data against soadyn::batch on 1 and 2 threads; and, after
// each K's rows, the machine's own 2-thread ceiling: a control loop that touches no memory and shares
// nothing (independent multiply-add chains in registers), its fixed work on 1 std::thread and split
// over 2, timed the same way.  One JSON object per line; tools/bench/batch.py runs it beside the
// Python side and makes the table.
//   soadyn_bench_batch MODEL.urdf FREE_ROOT(0|1) [MIN_SECONDS] [K …]
#include "soadyn/algorithm/batch.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/io/scenario_file.hpp"

#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <thread>
#include <vector>

using namespace soadyn;

namespace {

struct States {
  MatX Q, V, TAU;
};

States random_states(const Model& m, long K) {
  std::mt19937_64 gen(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  States s{MatX(m.nq, K), MatX(m.nv, K), MatX(m.nv, K)};
  for (long k = 0; k < K; ++k) {
    VecX q(m.nq);
    for (int i = 0; i < m.nq; ++i) q(i) = u(gen);
    m.normalize(q);
    s.Q.col(k) = q;
    for (int i = 0; i < m.nv; ++i) s.V(i, k) = u(gen), s.TAU(i, k) = 3 * u(gen);
  }
  return s;
}

// CPU time of the whole process (every thread), s
double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// states per second, and the process's CPU seconds per state in that window: what the threads
// spent, whatever share of the CPUs the scheduler gave them (work added by running on 2 threads,
// such as cache lines bounced between them, would show as more CPU per state than on 1)
struct Rate {
  double per_second = 0, cpu_per_state = 0;
};

// the best of three windows, each repeating f until it has run min_seconds
template <class F>
Rate rate(long K, double min_seconds, F&& f) {
  Rate best;
  for (int window = 0; window < 3; ++window) {
    long reps = 0;
    const double c0 = process_cpu_seconds();
    const auto t0 = std::chrono::steady_clock::now();
    double elapsed = 0;
    do {
      f();
      ++reps;
      elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    } while (elapsed < min_seconds);
    const double states = double(K) * double(reps);
    if (states / elapsed > best.per_second) best = {states / elapsed, (process_cpu_seconds() - c0) / states};
  }
  return best;
}

void print(const char* model, const char* what, long K, const char* how, Rate r) {
  std::printf("{\"model\": \"%s\", \"what\": \"%s\", \"K\": %ld, \"how\": \"%s\", \"states_per_second\": %.6g, "
              "\"cpu_seconds_per_state\": %.6g}\n",
              model, what, K, how, r.per_second, r.cpu_per_state);
  std::fflush(stdout);
}

// The control: n rounds of 8 independent multiply-add chains (FMA throughput, not one chain's
// latency), nothing read or written but registers; the result is returned so the loop stays.
double spin(long n, double seed) {
  double x[8];
  for (int j = 0; j < 8; ++j) x[j] = seed + j;
  for (long i = 0; i < n; ++i)
    for (int j = 0; j < 8; ++j) x[j] = x[j] * 0.999999999 + 1e-9;
  double sum = 0;
  for (double v : x) sum += v;
  return sum;
}

// rounds per second of `spin` on `threads` std::threads, each its share of a fixed amount of work
// (started and joined inside the timing, as Pool::run's threads are)
Rate spin_rate(int threads, double min_seconds) {
  const long rounds = 4'000'000;  // ~5 ms on one thread
  volatile double sink = 0;
  return rate(rounds, min_seconds, [&] {
    std::vector<std::thread> others;
    std::vector<double> result(size_t(threads) * 8, 0.0);  // each thread's result on its own cache line
    for (int t = 1; t < threads; ++t)
      others.emplace_back([&, t] { result[size_t(t) * 8] = spin(rounds / threads, t); });
    result[0] = spin(rounds / threads, 0);
    for (auto& t : others) t.join();
    for (int t = 0; t < threads; ++t) sink = sink + result[size_t(t) * 8];
  });
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s MODEL.urdf FREE_ROOT(0|1) [MIN_SECONDS] [K …]\n", argv[0]);
    return 2;
  }
  const std::string path = argv[1];
  const Model m = load_urdf(path, std::atoi(argv[2]) != 0, urdf_gravity());
  const double min_seconds = argc > 3 ? std::atof(argv[3]) : 0.1;
  std::vector<long> Ks;
  for (int a = 4; a < argc; ++a) Ks.push_back(std::atol(argv[a]));
  if (Ks.empty()) Ks = {1, 10, 100, 1000, 10000, 100000};
  const std::string name = path.substr(path.find_last_of('/') + 1);
  for (long K : Ks) {
    const States s = random_states(m, K);
    MatX QDD(m.nv, K), DQ(m.nv, m.nv * K), DV(m.nv, m.nv * K);
    // the C++ loop: one Data, the single-state calls
    Data data(m);
    DerivativeData dd(m);
    VecX q(m.nq), v(m.nv), tau(m.nv);
    print(name.c_str(), "qdd", K, "C++ loop", rate(K, min_seconds, [&] {
            for (long k = 0; k < K; ++k) {
              q = s.Q.col(k), v = s.V.col(k), tau = s.TAU.col(k);
              update_kinematics(m, data, q);
              update_velocities(m, data, v);
              forward_dynamics(m, data, tau, FdMethod::ArticulatedBody);
              QDD.col(k) = data.qdd;
            }
          }));
    print(name.c_str(), "dqdd", K, "C++ loop", rate(K, min_seconds, [&] {
            for (long k = 0; k < K; ++k) {
              q = s.Q.col(k), v = s.V.col(k), tau = s.TAU.col(k);
              update_kinematics(m, data, q);
              update_velocities(m, data, v);
              forward_dynamics_derivatives(m, data, v, tau, dd);
              DQ.middleCols(k * m.nv, m.nv) = dd.dqdd_dq;
              DV.middleCols(k * m.nv, m.nv) = dd.dqdd_dv;
            }
          }));
    for (int threads : {1, 2}) {
      batch::Pool pool(m, threads);  // kept across calls, as a caller in a loop would
      const std::string how = "C++ batch, " + std::to_string(threads) + " thread" + (threads > 1 ? "s" : "");
      print(name.c_str(), "qdd", K, how.c_str(),
            rate(K, min_seconds, [&] { batch::forward_dynamics(pool, s.Q, s.V, s.TAU, QDD); }));
      print(name.c_str(), "dqdd", K, how.c_str(),
            rate(K, min_seconds, [&] { batch::forward_dynamics_derivatives(pool, s.Q, s.V, s.TAU, DQ, DV); }));
    }
    // the control, beside this K's rows: what 2 threads give on this machine at this moment
    print("control", "spin", K, "1 thread", spin_rate(1, min_seconds));
    print("control", "spin", K, "2 threads", spin_rate(2, min_seconds));
  }
  return 0;
}
