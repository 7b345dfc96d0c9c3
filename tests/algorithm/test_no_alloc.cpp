// Once a Data exists, the algorithms allocate nothing.  The C allocator itself is replaced
// (malloc, calloc, realloc and the aligned variants, forwarding to glibc's __libc_* entry points),
// so every heap allocation is counted: operator new (which calls malloc) and Eigen's own
// aligned_malloc alike, in Release (NDEBUG) builds too, where Eigen's malloc guard is compiled out.
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/newton_solver.hpp"

#include "test_util.hpp"

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <vector>

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) {
  ++g_allocations;
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  ++g_allocations;
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  ++g_allocations;
  return __libc_realloc(p, n);
}
void* memalign(std::size_t alignment, std::size_t n) {
  ++g_allocations;
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) { return memalign(alignment, n); }
int posix_memalign(void** out, std::size_t alignment, std::size_t n) {
  void* p = memalign(alignment, n);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}
void free(void* p) { __libc_free(p); }
}

using namespace soadyn;
using namespace soadyn::test;

namespace {

// A region in which nothing may allocate: counts with our allocator and, if asked, arms Eigen's
// guard too (an eigen_assert: it only fires in builds without NDEBUG).
class Forbidden {
 public:
  explicit Forbidden(bool arm_eigen = true) : before_(g_allocations.load()), armed_(arm_eigen) { eigen_guard(false); }
  long end() {
    eigen_guard(true);
    return g_allocations.load() - before_;
  }

 private:
  void eigen_guard([[maybe_unused]] bool allowed) const {
#ifdef EIGEN_RUNTIME_NO_MALLOC
    if (armed_) Eigen::internal::set_is_malloc_allowed(allowed);
#endif
  }
  long before_;
  bool armed_;
};

TEST(NoAllocation, AlgorithmsAllocateNothingPerCall) {
  for (int variant = 0; variant < 4; ++variant) {
    const bool free_root = variant % 2 == 1;
    const double branching = variant < 2 ? 0.5 : 0.0;  // trees, and chains (the mass matrix's product path)
    Rng rng(3);
    const Model model = random_model(rng, {.n = 200, .branching = branching, .prismatic = 0.3, .free_root = free_root});
    Data data(model);
    const VecX q = random_q(rng, model), v = random_v(rng, model), tau = random_v(rng, model), qdd = random_v(rng, model);

    Forbidden region;
    mass_matrix(model, data, q);  // from q alone: the local route on trees, the inertial on chains
    bias_forces(model, data, q, v);
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
    mass_matrix(model, data);
    bias_forces(model, data);
    inverse_dynamics(model, data, qdd);
    for (FdMethod m : {FdMethod::Dense, FdMethod::Sparse, FdMethod::ArticulatedBody}) forward_dynamics(model, data, tau, m);
    inverse_dynamics(model, data, q, v, qdd);  // the one-call entry points, stage flags set and checked
    forward_dynamics(model, data, q, v, tau);
    const double e = kinetic_energy(model, data) + potential_energy(model, data);
    const Momentum h = momentum(model, data);
    EXPECT_EQ(region.end(), 0) << "free root " << free_root;
    EXPECT_TRUE(std::isfinite(e + h.linear.sum()));
  }
}

// frames.hpp: what a task-space controller calls each step, outputs sized once
TEST(NoAllocation, FramesAllocateNothingPerCall) {
  Rng rng(20);
  Model model = random_model(rng, {.n = 40, .prismatic = 0.2, .ball = 0.2, .free_root = true, .fixed = 5});
  const int f = model.add_frame("tool", model.nbodies - 1, {rng.rotation(), rng.vec3()});
  Data data(model);
  const VecX q = random_q(rng, model), v = random_v(rng, model), qdd = random_v(rng, model);
  MatX J(6, model.nv), Jc(3, model.nv), AG(6, model.nv), Jp(3, model.nv);
  Vec6 out, sum = Vec6::Zero();
  Forbidden region;
  update_kinematics(model, data, q);
  update_velocities(model, data, v);
  for (Reference r : {Reference::World, Reference::Local, Reference::LocalWorldAligned}) {
    frame_jacobian(model, data, f, r, J);
    frame_jacobian(model, data, q, f, r, J);  // from q: update_frames_to, then the same walk
    frame_jacobian_dot_times_v(model, data, f, r, out);
    sum += out + frame_velocity(model, data, f, r) + frame_acceleration(model, data, f, qdd, r, true);
  }
  point_jacobian(model, data, 0, Vec3(0.1, 0.2, 0.3), Jp);
  com_jacobian(model, data, Jc);
  centroidal_momentum_matrix(model, data, AG);
  sum += centroidal_momentum_matrix_dot_times_v(model, data) + centroidal_momentum(model, data);
  sum.head<3>() += frame_placement(model, data, f).p + com(model, data) + com_velocity(model, data);
  EXPECT_EQ(region.end(), 0);
  EXPECT_TRUE(sum.allFinite() && J.allFinite() && AG.allFinite());
}

TEST(NoAllocation, DerivativesAllocateNothingPerCall) {
  for (const bool chain : {false, true}) {
    Rng rng(5);
    const Model model = random_model(rng, {.n = 60, .branching = chain ? 0.0 : 0.5, .prismatic = 0.2, .ball = 0.2,
                                           .planar = 0.1, .free_root = true});
    Data data(model);
    DerivativeData dd(model);
    Inputs in;
    for (int i = 0; i < model.nbodies; ++i)
      if (model.nv_i[i] == 1) {
        in.springs.push_back({model.joint_names[i], model.idx_v[i], model.idx_q[i], 10.0, 0.0});
        in.dampers.push_back({model.joint_names[i], model.idx_v[i], 1.0});
      }
    const VecX q = random_q(rng, model), v = random_v(rng, model), tau = random_v(rng, model), qdd = random_v(rng, model);

    Forbidden region;
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
    inverse_dynamics_derivatives(model, data, v, qdd, dd);
    forward_dynamics_derivatives(model, data, v, tau, dd, &in, true);
    EXPECT_EQ(region.end(), 0) << "chain " << chain;
    EXPECT_TRUE(dd.dqdd_dq.allFinite() && dd.Minv.allFinite());
  }
}

// The Newton matrix's structured factorization and solves (CVODE BDF with the analytic Jacobian)
TEST(NoAllocation, NewtonSolverAllocatesNothingPerCall) {
  Rng rng(13);
  const Model model = random_model(rng, {.n = 40, .branching = 0.5, .prismatic = 0.2, .ball = 0.2, .free_root = true});
  Inputs in;
  for (int i = 0; i < model.nbodies; ++i)
    if (model.nv_i[i] == 1) in.dampers.push_back({model.joint_names[i], model.idx_v[i], 1.0});
  System sys(model, in, FdMethod::ArticulatedBody);
  NewtonSolver solver(model, sys.nquad);
  const VecX y = sys.state(random_q(rng, model), random_v(rng, model));
  MatX J(sys.size(), sys.size());
  VecX b = VecX::Random(sys.size()), x(sys.size());
  sys.prepare_jacobian();  // what the integrators that use ∂f/∂y do when they are made

  Forbidden region;
  sys.jacobian(0.0, y.data(), J);
  const bool structured = solver.set_jacobian(J);
  const bool ok = solver.factor(0.01);
  solver.solve(b, x);
  EXPECT_EQ(region.end(), 0);
  EXPECT_TRUE(structured && ok && x.allFinite());
}

// A fixed-step method's steps (here the symplectic Euler's Newton iterations, the heaviest) after
// the first: nothing allocates
TEST(NoAllocation, SymplecticEulerStepsAllocateNothing) {
  Rng rng(17);
  const Model model = random_model(rng, {.n = 12, .branching = 0.5, .prismatic = 0.2, .planar = 0.2});
  Inputs in;
  for (int i = 0; i < model.nbodies; ++i)
    if (model.nv_i[i] == 1) {
      in.springs.push_back({model.joint_names[i], model.idx_v[i], model.idx_q[i], 10.0, 0.0});
      in.dampers.push_back({model.joint_names[i], model.idx_v[i], 1.0});
      in.torques.push_back({model.joint_names[i], model.idx_v[i], 0.1, 0.5, 1.0, 0.0});
    }
  System sys(model, in, FdMethod::ArticulatedBody);
  SimulationSettings s;
  s.method = Method::SymplecticEuler;
  s.dt = 1e-3;
  VecX y = sys.state(random_q(rng, model), random_v(rng, model));
  double t = 0.0;
  auto integrator = make_integrator(s.method, sys, s, t, y);
  integrator->advance(s.dt, t, y);  // the first step sizes what it resizes

  Forbidden region;
  integrator->advance(0.01, t, y);
  EXPECT_EQ(region.end(), 0);
  EXPECT_EQ(integrator->stats().steps, 10);
  EXPECT_TRUE(y.allFinite());
}

volatile int g_size = 7;  // sizes the optimizer cannot see, so the allocations below cannot be elided
volatile double g_sink = 0;

// the counter itself works, in this very build: an Eigen heap vector, a std::vector and a Data
// inside a forbidden region are all seen
TEST(NoAllocation, CounterSeesEigenAndStdAllocations) {
  {
    Forbidden region(false);
    VecX x = VecX::LinSpaced(g_size, 0.0, 1.0);  // Eigen: aligned_malloc → malloc
    g_sink = x.sum();
    const long n = region.end();
    EXPECT_GE(n, 1) << "an Eigen VectorXd was not counted";
  }
  {
    Forbidden region(false);
    std::vector<double> y(std::size_t(g_size), 1.0);  // operator new → malloc
    g_sink = y.back();
    EXPECT_GE(region.end(), 1) << "a std::vector was not counted";
  }
  Rng rng(4);
  const Model model = random_model(rng, {.n = 5});
  Forbidden region(false);
  Data data(model);
  g_sink = double(data.M.size());
  EXPECT_GT(region.end(), 0) << "a Data was not counted";
}

}  // namespace
