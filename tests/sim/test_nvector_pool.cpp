// The pool of CVODE's vectors (src/sim/nvector_pool.hpp): its vectors are serial vectors with the
// compiled operations, clones of clones stay in the pool, a destroyed vector is the next clone,
// lengths keep apart, operations on them agree with SUNDIALS' own vectors, a pool's array is a
// ColumnBlock in place and any other one a copy, and the entries of vectors never written cost no
// memory (the resident size, read from /proc).
#include "../../src/sim/nvector_ops.hpp"
#include "../../src/sim/nvector_pool.hpp"

#include <gtest/gtest.h>

#include <sundials/sundials_context.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <unistd.h>
#include <vector>

namespace {

using soadyn::nvector_ops::VectorPool;

struct Context {
  SUNContext ctx = nullptr;
  Context() { SUNContext_Create(nullptr, &ctx); }
  ~Context() { SUNContext_Free(&ctx); }
};

// resident bytes of this process
long resident() {
  long pages = 0, rss = 0;
  FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return -1;
  const int got = std::fscanf(f, "%ld %ld", &pages, &rss);
  std::fclose(f);
  return got == 2 ? rss * sysconf(_SC_PAGESIZE) : -1;
}

TEST(NvectorPool, VectorsAreSerialWithTheCompiledOperations) {
  Context c;
  VectorPool pool;
  N_Vector v = pool.make(37, c.ctx);
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(N_VGetVectorID(v), SUNDIALS_NVEC_SERIAL);
  EXPECT_EQ(N_VGetLength(v), 37);
  EXPECT_EQ(N_VGetArrayPointer(v), NV_DATA_S(v));
  EXPECT_FALSE(NV_OWN_DATA_S(v));
  N_Vector compiled = soadyn::nvector_ops::new_vector(37, c.ctx);
  EXPECT_EQ(v->ops->nvlinearsum, compiled->ops->nvlinearsum);
  EXPECT_EQ(v->ops->nvwrmsnormvectorarray, compiled->ops->nvwrmsnormvectorarray);
  EXPECT_EQ(v->ops->nvlinearcombination, compiled->ops->nvlinearcombination);  // fused operations on
  N_VDestroy(compiled);
  N_VDestroy(v);
  EXPECT_EQ(pool.live(), 0);
}

TEST(NvectorPool, ClonesStayInThePoolAndADestroyedVectorIsTheNextClone) {
  Context c;
  VectorPool pool;
  N_Vector v = pool.make(5, c.ctx);
  N_Vector w = N_VClone(v);
  N_Vector x = N_VClone(w);  // a clone of a clone
  EXPECT_EQ(pool.live(), 3);
  EXPECT_EQ(x->ops->nvclone, v->ops->nvclone);
  EXPECT_EQ(N_VGetLength(x), 5);
  // distinct entries
  N_VConst(1.0, v), N_VConst(2.0, w), N_VConst(3.0, x);
  EXPECT_EQ(NV_Ith_S(v, 4), 1.0);
  EXPECT_EQ(NV_Ith_S(w, 4), 2.0);
  EXPECT_EQ(NV_Ith_S(x, 0), 3.0);
  double* w_data = NV_DATA_S(w);
  N_VDestroy(w);
  EXPECT_EQ(pool.live(), 2);
  N_Vector y = N_VClone(v);
  EXPECT_EQ(NV_DATA_S(y), w_data);
  // another length, its own entries; an empty clone has none until it is given some
  N_Vector z = pool.make(3, c.ctx);
  N_Vector e = N_VCloneEmpty(z);
  EXPECT_EQ(N_VGetLength(e), 3);
  EXPECT_EQ(N_VGetArrayPointer(e), nullptr);
  double outside[3] = {0, 0, 0};
  N_VSetArrayPointer(outside, e);
  N_VConst(4.0, e);
  EXPECT_EQ(outside[2], 4.0);
  N_VDestroy(e);  // not the caller's array: nothing freed
  EXPECT_EQ(outside[2], 4.0);
  N_Vector again = N_VClone(z);
  EXPECT_NE(N_VGetArrayPointer(again), nullptr);  // the node the empty clone had, with its own entries again
  EXPECT_NE(N_VGetArrayPointer(again), outside);
  for (N_Vector u : {v, x, y, z, again}) N_VDestroy(u);
  EXPECT_EQ(pool.live(), 0);
}

TEST(NvectorPool, VectorArrayOperationsAgreeWithTheLibrarysVectors) {
  Context c;
  VectorPool pool;
  constexpr int n = 101, k = 10;
  N_Vector t = pool.make(n, c.ctx);
  N_Vector* X = N_VCloneVectorArray(k, t);
  N_Vector* Y = N_VCloneVectorArray(k, t);
  N_Vector lt = N_VNew_Serial(n, c.ctx);
  N_Vector* LX = N_VCloneVectorArray(k, lt);
  N_Vector* LY = N_VCloneVectorArray(k, lt);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < n; ++i) {
      NV_Ith_S(X[j], i) = NV_Ith_S(LX[j], i) = u(rng);
      NV_Ith_S(Y[j], i) = NV_Ith_S(LY[j], i) = u(rng);
    }
  // a pool's array lies in one piece, so linear_sum_array takes its one loop; the library's does not
  ASSERT_NE(soadyn::nvector_ops::detail::contiguous(k, X), nullptr);
  ASSERT_EQ(soadyn::nvector_ops::detail::contiguous(k, LX), nullptr);
  N_VLinearSumVectorArray(k, 0.5, X, -2.0, Y, X);
  N_VLinearSumVectorArray(k, 0.5, LX, -2.0, LY, LX);
  // out of order, the same vectors take the loop per vector
  std::vector<N_Vector> RX(X, X + k), RY(Y, Y + k), RLX(LX, LX + k), RLY(LY, LY + k);
  std::reverse(RX.begin(), RX.end()), std::reverse(RY.begin(), RY.end());
  std::reverse(RLX.begin(), RLX.end()), std::reverse(RLY.begin(), RLY.end());
  ASSERT_EQ(soadyn::nvector_ops::detail::contiguous(k, RX.data()), nullptr);
  N_VLinearSumVectorArray(k, -1.5, RY.data(), 0.25, RX.data(), RX.data());
  N_VLinearSumVectorArray(k, -1.5, RLY.data(), 0.25, RLX.data(), RLX.data());
  std::vector<double> norms(k), lnorms(k);
  N_VConst(0.7, t), N_VConst(0.7, lt);
  std::vector<N_Vector> W(k, t), LW(k, lt);
  N_VWrmsNormVectorArray(k, X, W.data(), norms.data());
  N_VWrmsNormVectorArray(k, LX, LW.data(), lnorms.data());
  for (int j = 0; j < k; ++j) {
    EXPECT_NEAR(norms[size_t(j)], lnorms[size_t(j)], 1e-14 * lnorms[size_t(j)]);
    for (int i = 0; i < n; ++i) EXPECT_NEAR(NV_Ith_S(X[j], i), NV_Ith_S(LX[j], i), 1e-15);
  }
  N_VDestroyVectorArray(X, k), N_VDestroyVectorArray(Y, k), N_VDestroy(t);
  N_VDestroyVectorArray(LX, k), N_VDestroyVectorArray(LY, k), N_VDestroy(lt);
  EXPECT_EQ(pool.live(), 0);
}

// ColumnBlock, how the sensitivities' right-hand side sees CVODES' arrays: a pool's array is the
// block itself (writes through it land in the vectors, the scratch is never used); the library's
// array and the pool's out of order go through the scratch, load() reading each vector into its
// column and store() writing each column back, nothing else touched
TEST(NvectorPool, ColumnBlockIsAPoolArrayInPlaceAndCopiesAnyOther) {
  using soadyn::nvector_ops::ColumnBlock;
  Context c;
  VectorPool pool;
  constexpr int n = 37, k = 5;
  N_Vector t = pool.make(n, c.ctx);
  N_Vector* X = N_VCloneVectorArray(k, t);
  N_Vector lt = N_VNew_Serial(n, c.ctx);
  N_Vector* LX = N_VCloneVectorArray(k, lt);
  std::vector<N_Vector> RX(X, X + k);
  std::reverse(RX.begin(), RX.end());
  const auto entry = [](int j, int i) { return 1000.0 * j + i + 0.5; };
  {
    std::vector<double> scratch;
    const ColumnBlock b(k, X, n, scratch);
    ASSERT_TRUE(b.in_place());
    EXPECT_EQ(b.data(), NV_DATA_S(X[0]));
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < n; ++i) b.data()[j * n + i] = entry(j, i);
    b.load(), b.store();
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < n; ++i) EXPECT_EQ(NV_Ith_S(X[j], i), entry(j, i)) << "pool vector " << j << " entry " << i;
    EXPECT_TRUE(scratch.empty());
  }
  for (N_Vector* V : {LX, RX.data()}) {
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < n; ++i) NV_Ith_S(V[j], i) = entry(j, i);
    std::vector<double> scratch;
    const ColumnBlock b(k, V, n, scratch);
    ASSERT_FALSE(b.in_place());
    ASSERT_EQ(b.data(), scratch.data());
    ASSERT_EQ(scratch.size(), size_t(n * k));
    b.load();
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < n; ++i) {
        EXPECT_EQ(b.data()[j * n + i], entry(j, i)) << "column " << j << " row " << i;
        b.data()[j * n + i] = -2.0 * entry(j, i);
      }
    for (int j = 0; j < k; ++j) EXPECT_EQ(NV_Ith_S(V[j], 0), entry(j, 0)) << "written before store";
    b.store();
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < n; ++i) EXPECT_EQ(NV_Ith_S(V[j], i), -2.0 * entry(j, i)) << "vector " << j << " entry " << i;
  }
  N_VDestroyVectorArray(X, k), N_VDestroy(t);
  N_VDestroyVectorArray(LX, k), N_VDestroy(lt);
  EXPECT_EQ(pool.live(), 0);
}

TEST(NvectorPool, EntriesNeverWrittenCostNoMemory) {
  Context c;
  VectorPool pool;
  constexpr long n = 1000, count = 20000;  // 160 MB of entries
  const long before = resident();
  ASSERT_GT(before, 0);
  N_Vector t = pool.make(n, c.ctx);
  std::vector<N_Vector> v(static_cast<size_t>(count));
  for (auto& x : v) x = N_VClone(t);
  EXPECT_GE(pool.reserved(), n * count);
  const long grown = resident() - before;
  EXPECT_LT(grown, 16L << 20) << "resident size grew by " << grown << " bytes";  // headers only: ~2 MB
  // writing some of them touches their entries, and only theirs
  for (long j = 0; j < 1000; ++j) N_VConst(1.0, v[size_t(j)]);
  const long written = resident() - before - grown;
  EXPECT_GT(written, 1000 * n * 8 / 2);
  for (auto& x : v) N_VDestroy(x);
  N_VDestroy(t);
}

}  // namespace
