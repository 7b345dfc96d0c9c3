// Once a Data exists, the algorithms allocate nothing: a counting global operator new catches
// every heap allocation (std and Eigen alike), and Eigen's own guard is armed too.
#include "test_util.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

using namespace soadyn;
using namespace soadyn::test;

namespace {

TEST(NoAllocation, AlgorithmsAllocateNothingPerCall) {
  for (int variant = 0; variant < 4; ++variant) {
    const bool free_root = variant % 2 == 1;
    const double branching = variant < 2 ? 0.5 : 0.0;  // trees, and chains (the mass matrix's product path)
    Rng rng(3);
    const Model model = random_model(rng, {.n = 200, .branching = branching, .prismatic = 0.3, .free_root = free_root});
    Data data(model);
    const VecX q = random_q(rng, model), v = random_v(rng, model), tau = random_v(rng, model), qdd = random_v(rng, model);

    const long before = g_allocations.load();
    Eigen::internal::set_is_malloc_allowed(false);
    update_kinematics(model, data, q);
    update_velocities(model, data, v);
    mass_matrix(model, data);
    bias_forces(model, data);
    inverse_dynamics(model, data, qdd);
    for (FdMethod m : {FdMethod::Dense, FdMethod::Sparse, FdMethod::ArticulatedBody}) forward_dynamics(model, data, tau, m);
    const double e = kinetic_energy(model, data) + potential_energy(model, data);
    const Momentum h = momentum(model, data);
    Eigen::internal::set_is_malloc_allowed(true);
    EXPECT_EQ(g_allocations.load() - before, 0) << "free root " << free_root;
    EXPECT_TRUE(std::isfinite(e + h.linear.sum()));
  }
}

// the counter itself works: a Data does allocate
TEST(NoAllocation, CounterSeesAllocations) {
  Rng rng(4);
  const Model model = random_model(rng, {.n = 5});
  const long before = g_allocations.load();
  Data data(model);
  EXPECT_GT(g_allocations.load() - before, 0);
}

}  // namespace
