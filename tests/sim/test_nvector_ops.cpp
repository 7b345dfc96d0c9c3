// The compiled serial vector operations (src/sim/nvector_ops.hpp) against SUNDIALS' own: each of the
// 35 installed operations on the same random vectors, including the in-place cases CVODE uses (z = x,
// Z = Y, z = X_0), agrees with the library's to rounding, as do the error weights CVodeWFtolerances
// is given; and a clone carries the compiled table.
#include "../../src/sim/nvector_ops.hpp"

#include <gtest/gtest.h>

#include <sundials/sundials_context.h>

#include <limits>
#include <memory>
#include <random>
#include <vector>

namespace {

namespace ops = soadyn::nvector_ops;

struct Context {
  SUNContext ctx = nullptr;
  Context() { SUNContext_Create(nullptr, &ctx); }
  ~Context() { SUNContext_Free(&ctx); }
};
struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
using Vector = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;

constexpr sunindextype kN = 37;  // not a multiple of any SIMD width

class NvectorOps : public ::testing::Test {
 protected:
  Context c;
  std::mt19937 rng{7};
  // the library's vector (fused operations on) and the compiled one, with the same entries
  Vector library(const std::vector<double>& x) {
    N_Vector v = N_VNew_Serial(kN, c.ctx);
    N_VEnableFusedOps_Serial(v, SUNTRUE);
    std::copy(x.begin(), x.end(), NV_DATA_S(v));
    return Vector(v);
  }
  Vector compiled(const std::vector<double>& x) {
    N_Vector v = ops::new_vector(kN, c.ctx);
    std::copy(x.begin(), x.end(), NV_DATA_S(v));
    return Vector(v);
  }
  std::vector<double> random(double lo = -2.0, double hi = 2.0) {
    std::uniform_real_distribution<double> u(lo, hi);
    std::vector<double> x(static_cast<size_t>(kN));
    for (auto& e : x) e = u(rng);
    return x;
  }
  static void expect_same(N_Vector a, N_Vector b, const char* what) {
    for (sunindextype i = 0; i < kN; ++i)
      EXPECT_NEAR(NV_Ith_S(a, i), NV_Ith_S(b, i), 1e-14 * (1.0 + std::abs(NV_Ith_S(a, i)))) << what << " entry " << i;
  }
};

TEST_F(NvectorOps, ElementwiseOperationsAgreeWithTheLibrarys) {
  const auto x = random(), y = random(), w = random(0.1, 3.0);
  auto lx = library(x), ly = library(y), lz = library(random());
  auto cx = compiled(x), cy = compiled(y), cz = compiled(random());
  const auto both = [&](auto&& op, const char* what) {
    op(lx.get(), ly.get(), lz.get());
    op(cx.get(), cy.get(), cz.get());
    expect_same(lz.get(), cz.get(), what);
  };
  both([](N_Vector a, N_Vector b, N_Vector z) { N_VLinearSum(0.3, a, -1.7, b, z); }, "linear sum");
  both([](N_Vector a, N_Vector b, N_Vector) { N_VLinearSum(2.0, a, 1.0, b, b); }, "linear sum into y");
  expect_same(ly.get(), cy.get(), "linear sum into y");
  both([](N_Vector a, N_Vector b, N_Vector z) { N_VProd(a, b, z); }, "prod");
  both([](N_Vector a, N_Vector b, N_Vector z) { N_VDiv(a, b, z); }, "div");
  both([](N_Vector a, N_Vector, N_Vector z) { N_VScale(-0.25, a, z); }, "scale");
  both([](N_Vector, N_Vector, N_Vector z) { N_VScale(3.0, z, z); }, "scale in place");
  both([](N_Vector a, N_Vector, N_Vector z) { N_VAbs(a, z); }, "abs");
  both([](N_Vector a, N_Vector, N_Vector z) { N_VInv(a, z); }, "inv");
  both([](N_Vector a, N_Vector, N_Vector z) { N_VAddConst(a, 0.5, z); }, "add const");
  both([](N_Vector a, N_Vector, N_Vector z) { N_VCompare(1.0, a, z); }, "compare");
  both([](N_Vector, N_Vector, N_Vector z) { N_VConst(4.5, z); }, "const");
  auto lw = library(w), cw = compiled(w);
  EXPECT_NEAR(N_VDotProd(lx.get(), ly.get()), N_VDotProd(cx.get(), cy.get()), 1e-13);
  EXPECT_EQ(N_VMaxNorm(lx.get()), N_VMaxNorm(cx.get()));
  EXPECT_EQ(N_VMin(lx.get()), N_VMin(cx.get()));
  EXPECT_NEAR(N_VL1Norm(lx.get()), N_VL1Norm(cx.get()), 1e-13);
  EXPECT_NEAR(N_VWrmsNorm(lx.get(), lw.get()), N_VWrmsNorm(cx.get(), cw.get()), 1e-14);
  EXPECT_NEAR(N_VWL2Norm(lx.get(), lw.get()), N_VWL2Norm(cx.get(), cw.get()), 1e-13);
  EXPECT_NEAR(N_VWrmsNormMask(lx.get(), lw.get(), ly.get()), N_VWrmsNormMask(cx.get(), cw.get(), cy.get()), 1e-14);
  EXPECT_NEAR(N_VWSqrSumLocal(lx.get(), lw.get()), N_VWSqrSumLocal(cx.get(), cw.get()), 1e-13);
  EXPECT_NEAR(N_VWSqrSumMaskLocal(lx.get(), lw.get(), ly.get()), N_VWSqrSumMaskLocal(cx.get(), cw.get(), cy.get()), 1e-13);
  EXPECT_NEAR(N_VDotProdLocal(lx.get(), ly.get()), N_VDotProdLocal(cx.get(), cy.get()), 1e-13);
  EXPECT_EQ(N_VMaxNormLocal(lx.get()), N_VMaxNormLocal(cx.get()));
  EXPECT_EQ(N_VMinLocal(lx.get()), N_VMinLocal(cx.get()));
  EXPECT_NEAR(N_VL1NormLocal(lx.get()), N_VL1NormLocal(cx.get()), 1e-13);
  // inverse with a zero entry: false, that entry of z untouched, the rest inverted
  auto z0 = x;
  z0[5] = 0.0;
  auto lz0 = library(z0), cz0 = compiled(z0);
  N_VConst(9.0, lz.get()), N_VConst(9.0, cz.get());
  EXPECT_EQ(N_VInvTest(lz0.get(), lz.get()), SUNFALSE);
  EXPECT_EQ(N_VInvTest(cz0.get(), cz.get()), SUNFALSE);
  expect_same(lz.get(), cz.get(), "inv test");
  EXPECT_EQ(NV_Ith_S(cz.get(), 5), 9.0);
  EXPECT_EQ(N_VInvTest(cx.get(), cz.get()), SUNTRUE);
  N_VConst(9.0, lz.get()), N_VConst(9.0, cz.get());
  EXPECT_EQ(N_VInvTestLocal(lz0.get(), lz.get()), N_VInvTestLocal(cz0.get(), cz.get()));
  expect_same(lz.get(), cz.get(), "inv test local");
}

TEST_F(NvectorOps, FusedAndVectorArrayOperationsAgreeWithTheLibrarys) {
  constexpr int k = 5, nsum = 4;
  std::vector<std::vector<double>> xs;
  for (int j = 0; j < k * nsum + k; ++j) xs.push_back(random());
  std::vector<Vector> L, C;
  for (const auto& x : xs) L.push_back(library(x)), C.push_back(compiled(x));
  const auto vecs = [](std::vector<Vector>& v, int from, int count) {
    std::vector<N_Vector> out;
    for (int j = 0; j < count; ++j) out.push_back(v[size_t(from + j)].get());
    return out;
  };
  std::vector<double> c{0.5, -1.25, 2.0, 0.75, -0.3};
  const auto check = [&](int from, int count, const char* what) {
    for (int j = from; j < from + count; ++j) expect_same(L[size_t(j)].get(), C[size_t(j)].get(), what);
  };
  // z = Σ c_k X_k: into a fresh z, and in place into X_0 (c_0 ≠ 1 and = 1)
  for (auto* V : {&L, &C}) {
    auto X = vecs(*V, 0, k);
    N_VLinearCombination(k, c.data(), X.data(), (*V)[size_t(k)].get());
    N_VLinearCombination(k - 1, c.data() + 1, X.data() + 1, (*V)[size_t(k + 1)].get());
    double one[3] = {1.0, 0.5, -2.0};
    N_VLinearCombination(3, one, X.data(), X[0]);
    N_VLinearCombination(3, c.data(), X.data() + 1, X[1]);
  }
  check(0, k + 2, "linear combination");
  // Z_k = a_k x + Y_k, into Z and in place (Z = Y); x·Y_k
  for (auto* V : {&L, &C}) {
    auto Y = vecs(*V, 0, k), Z = vecs(*V, k, k);
    N_VScaleAddMulti(k, c.data(), (*V)[size_t(2 * k)].get(), Y.data(), Z.data());
    N_VScaleAddMulti(k, c.data(), (*V)[size_t(2 * k)].get(), Y.data(), Y.data());
  }
  check(0, 2 * k, "scale add multi");
  double dl[k], dc[k];
  {
    auto Yl = vecs(L, 0, k), Yc = vecs(C, 0, k);
    N_VDotProdMulti(k, L[size_t(2 * k)].get(), Yl.data(), dl);
    N_VDotProdMulti(k, C[size_t(2 * k)].get(), Yc.data(), dc);
    for (int j = 0; j < k; ++j) EXPECT_NEAR(dl[j], dc[j], 1e-13) << "dot multi " << j;
    N_VDotProdMultiLocal(k, L[size_t(2 * k)].get(), Yl.data(), dl);
    N_VDotProdMultiLocal(k, C[size_t(2 * k)].get(), Yc.data(), dc);
    for (int j = 0; j < k; ++j) EXPECT_NEAR(dl[j], dc[j], 1e-13) << "dot multi local " << j;
  }
  // vector arrays
  for (auto* V : {&L, &C}) {
    auto X = vecs(*V, 0, k), Y = vecs(*V, k, k), Z = vecs(*V, 2 * k, k);
    N_VLinearSumVectorArray(k, 0.7, X.data(), -1.3, Y.data(), Z.data());
    N_VLinearSumVectorArray(k, 0.7, X.data(), 1.0, Y.data(), Y.data());
    N_VScaleVectorArray(k, c.data(), Z.data(), X.data());
    N_VConstVectorArray(k - 2, -0.125, Y.data() + 1);
  }
  check(0, 3 * k, "linear sum / scale / const vector array");
  {
    auto Xl = vecs(L, 0, k), Wl = vecs(L, k, k), Xc = vecs(C, 0, k), Wc = vecs(C, k, k);
    double ml[k], mc[k];
    N_VWrmsNormVectorArray(k, Xl.data(), Wl.data(), ml);
    N_VWrmsNormVectorArray(k, Xc.data(), Wc.data(), mc);
    for (int j = 0; j < k; ++j) EXPECT_NEAR(ml[j], mc[j], 1e-14) << "wrms array " << j;
    N_VWrmsNormMaskVectorArray(k, Xl.data(), Wl.data(), L[size_t(2 * k)].get(), ml);
    N_VWrmsNormMaskVectorArray(k, Xc.data(), Wc.data(), C[size_t(2 * k)].get(), mc);
    for (int j = 0; j < k; ++j) EXPECT_NEAR(ml[j], mc[j], 1e-14) << "wrms mask array " << j;
  }
  // Z[j][i] = a_j X_i + Y[j][i], into Z and in place; Z_i = Σ_j c_j X[j][i], into Z and into X[0]
  for (auto* V : {&L, &C}) {
    auto X = vecs(*V, 0, k);
    std::vector<std::vector<N_Vector>> Yr, Zr;
    for (int j = 0; j < nsum - 1; ++j) Yr.push_back(vecs(*V, k * (j + 1), k));
    Zr.push_back(vecs(*V, k * nsum, k));
    for (int j = 1; j < nsum - 1; ++j) Zr.push_back(Yr[size_t(j)]);
    std::vector<N_Vector*> Y, Z;
    for (auto& r : Yr) Y.push_back(r.data());
    for (auto& r : Zr) Z.push_back(r.data());
    N_VScaleAddMultiVectorArray(k, nsum - 1, c.data(), X.data(), Y.data(), Z.data());
    N_VScaleAddMultiVectorArray(k, nsum - 1, c.data(), X.data(), Y.data(), Y.data());
    std::vector<N_Vector*> XX{X.data()};
    for (auto& r : Yr) XX.push_back(r.data());
    N_VLinearCombinationVectorArray(k, nsum, c.data(), XX.data(), Zr[0].data());
    N_VLinearCombinationVectorArray(k, nsum, c.data(), XX.data(), X.data());
    double one[4] = {1.0, -0.5, 0.25, 2.0};
    N_VLinearCombinationVectorArray(k, nsum, one, XX.data(), X.data());
  }
  check(0, k * (nsum + 1), "scale add multi / linear combination vector array");
}

// CVODE's error weights for scalar tolerances, as cvEwtSetSS forms them with the library's
// operations (|y|, ·rtol, +atol, 1/x), against the one-pass loop CVodeWFtolerances is given
TEST_F(NvectorOps, ErrorWeightsAreTheLibrarysScalarTolerancesWeights) {
  for (const double atol : {1e-10, 1e-3}) {
    auto y = random(-300.0, 300.0);
    y[3] = 0.0;  // atol alone
    auto ly = library(y), lw = library(random()), cy = compiled(y), cw = compiled(random());
    N_VAbs(ly.get(), lw.get());
    N_VScale(1e-8, lw.get(), lw.get());
    N_VAddConst(lw.get(), atol, lw.get());
    N_VInv(lw.get(), lw.get());
    ops::error_weights(1e-8, atol, cy.get(), cw.get());
    expect_same(lw.get(), cw.get(), "error weights");
    EXPECT_DOUBLE_EQ(NV_Ith_S(cw.get(), 3), 1.0 / atol);
  }
}

TEST_F(NvectorOps, ACloneCarriesTheCompiledOperations) {
  auto v = compiled(random());
  Vector w(N_VClone(v.get()));
  EXPECT_EQ(w->ops->nvlinearsum, v->ops->nvlinearsum);
  EXPECT_EQ(w->ops->nvscaleaddmultivectorarray, v->ops->nvscaleaddmultivectorarray);
  auto l = library(random());
  EXPECT_NE(w->ops->nvlinearsum, l->ops->nvlinearsum);
  EXPECT_NE(w->ops->nvwrmsnormvectorarray, l->ops->nvwrmsnormvectorarray);
}

// all_finite, the test on the bits the sensitivity and state right-hand sides end with: true for
// every finite double (zeros of both signs, subnormals, the largest), false for NaN or ±inf at any
// position, as std::isfinite says entry by entry
TEST(NvectorOpsAllFinite, FindsNanAndInfinityAtAnyPosition) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  const double specials[] = {0.0, -0.0, std::numeric_limits<double>::denorm_min(), -std::numeric_limits<double>::max(),
                             std::numeric_limits<double>::max(), std::numeric_limits<double>::min()};
  const double bad[] = {std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::quiet_NaN(),
                        std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const sunindextype n : {sunindextype(1), sunindextype(7), kN, sunindextype(1000)}) {
    std::vector<double> x(static_cast<size_t>(n));
    for (sunindextype i = 0; i < n; ++i) x[size_t(i)] = i % 5 == 0 ? specials[size_t(i / 5) % 6] : u(rng);
    EXPECT_TRUE(ops::all_finite(x.data(), n)) << "n " << n;
    for (const sunindextype at : {sunindextype(0), n / 2, n - 1})
      for (const double b : bad) {
        const double keep = x[size_t(at)];
        x[size_t(at)] = b;
        EXPECT_FALSE(ops::all_finite(x.data(), n)) << "n " << n << ", " << b << " at " << at;
        EXPECT_TRUE(ops::all_finite(x.data(), at)) << "the entries before it";
        x[size_t(at)] = keep;
      }
  }
}

}  // namespace
