// Compiled loops for the serial N_Vector's operations, installed on every vector CVODE(S) works
// with (cvode.hpp, adjoint.cpp).  Debian 12's SUNDIALS 6.4 libraries are built without optimization
// (each element of a vector operation goes through the stack), and those operations were about 40 %
// of a plain CVODE run of the 7-DOF arm and half of a forward-sensitivity run.  The loops are
// SUNDIALS' own definitions (nvector_serial.c), element by element in the same order, so sums and
// norms come out as SUNDIALS' do up to the rounding of a contracted multiply-add (the weighted sum
// of squares in eight partial sums: wsqr_sum);
// test_nvector_ops checks each against the library's.  The constraint operations (constrmask,
// minquotient), which soadyn never asks for, stay the library's.
#pragma once

#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace soadyn::nvector_ops {

namespace detail {

inline sunindextype length(N_Vector v) { return NV_LENGTH_S(v); }
inline realtype* data(N_Vector v) { return NV_DATA_S(v); }

// z = a x + b y (z may be x or y: each element is read before it is written)
inline void linear_sum(realtype a, N_Vector x, realtype b, N_Vector y, N_Vector z) {
  const sunindextype n = length(z);
  const realtype *xd = data(x), *yd = data(y);
  realtype* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
}
inline void constant(realtype c, N_Vector z) { std::fill_n(data(z), length(z), c); }
inline void prod(N_Vector x, N_Vector y, N_Vector z) {
  const sunindextype n = length(z);
  const realtype *xd = data(x), *yd = data(y);
  realtype* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = xd[i] * yd[i];
}
inline void div(N_Vector x, N_Vector y, N_Vector z) {
  const sunindextype n = length(z);
  const realtype *xd = data(x), *yd = data(y);
  realtype* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = xd[i] / yd[i];
}
inline void scale(realtype c, N_Vector x, N_Vector z) {
  const sunindextype n = length(z);
  const realtype* xd = data(x);
  realtype* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = c * xd[i];
}
inline void abs(N_Vector x, N_Vector z) {
  const sunindextype n = length(z);
  const realtype* xd = data(x);
  realtype* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = std::abs(xd[i]);
}
inline void inv(N_Vector x, N_Vector z) {
  const sunindextype n = length(z);
  const realtype* xd = data(x);
  realtype* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = 1.0 / xd[i];
}
inline void add_const(N_Vector x, realtype b, N_Vector z) {
  const sunindextype n = length(z);
  const realtype* xd = data(x);
  realtype* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = xd[i] + b;
}
inline realtype dot(N_Vector x, N_Vector y) {
  const sunindextype n = length(x);
  const realtype *xd = data(x), *yd = data(y);
  realtype s = 0;
  for (sunindextype i = 0; i < n; ++i) s += xd[i] * yd[i];
  return s;
}
inline realtype max_norm(N_Vector x) {
  const sunindextype n = length(x);
  const realtype* xd = data(x);
  realtype m = 0;
  for (sunindextype i = 0; i < n; ++i) m = std::max(m, std::abs(xd[i]));
  return m;
}
// Σ (x_i w_i)², over the entries with id_i > 0 when id is given.  Eight partial sums (entry i
// into sum i mod 8, the remainder into the first) added pairwise at the end: one running sum, as
// SUNDIALS keeps, waits a multiply-add's latency per entry, and the error tests take norms of
// every sensitivity each step; the result differs from SUNDIALS' by rounding only
inline realtype wsqr_sum(N_Vector x, N_Vector w) {
  const sunindextype n = length(x);
  const realtype *xd = data(x), *wd = data(w);
  realtype s[8] = {};
  sunindextype i = 0;
  for (; i + 8 <= n; i += 8)
    for (int l = 0; l < 8; ++l) {
      const realtype p = xd[i + l] * wd[i + l];
      s[l] += p * p;
    }
  for (; i < n; ++i) {
    const realtype p = xd[i] * wd[i];
    s[0] += p * p;
  }
  return ((s[0] + s[4]) + (s[1] + s[5])) + ((s[2] + s[6]) + (s[3] + s[7]));
}
inline realtype wsqr_sum_mask(N_Vector x, N_Vector w, N_Vector id) {
  const sunindextype n = length(x);
  const realtype *xd = data(x), *wd = data(w), *idd = data(id);
  realtype s = 0;
  for (sunindextype i = 0; i < n; ++i)
    if (idd[i] > 0) {
      const realtype p = xd[i] * wd[i];
      s += p * p;
    }
  return s;
}
inline realtype wrms_norm(N_Vector x, N_Vector w) { return std::sqrt(wsqr_sum(x, w) / realtype(length(x))); }
inline realtype wrms_norm_mask(N_Vector x, N_Vector w, N_Vector id) {
  return std::sqrt(wsqr_sum_mask(x, w, id) / realtype(length(x)));
}
inline realtype min(N_Vector x) {
  const sunindextype n = length(x);
  const realtype* xd = data(x);
  realtype m = xd[0];
  for (sunindextype i = 1; i < n; ++i) m = std::min(m, xd[i]);
  return m;
}
inline realtype wl2_norm(N_Vector x, N_Vector w) { return std::sqrt(wsqr_sum(x, w)); }
inline realtype l1_norm(N_Vector x) {
  const sunindextype n = length(x);
  const realtype* xd = data(x);
  realtype s = 0;
  for (sunindextype i = 0; i < n; ++i) s += std::abs(xd[i]);
  return s;
}
inline void compare(realtype c, N_Vector x, N_Vector z) {
  const sunindextype n = length(z);
  const realtype* xd = data(x);
  realtype* zd = data(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = std::abs(xd[i]) >= c ? 1.0 : 0.0;
}
// z = 1/x where x ≠ 0; false if some x_i = 0 (z_i then left as it was)
inline booleantype inv_test(N_Vector x, N_Vector z) {
  const sunindextype n = length(z);
  const realtype* xd = data(x);
  realtype* zd = data(z);
  booleantype none_zero = SUNTRUE;
  for (sunindextype i = 0; i < n; ++i) {
    if (xd[i] == 0.0) none_zero = SUNFALSE;
    else zd[i] = 1.0 / xd[i];
  }
  return none_zero;
}

// z = Σ_k c_k X_k; z may be X_0 (and no other X_k)
inline int linear_combination(int nvec, realtype* c, N_Vector* X, N_Vector z) {
  const sunindextype n = length(z);
  realtype* zd = data(z);
  if (X[0] == z) {
    if (c[0] != 1.0)
      for (sunindextype i = 0; i < n; ++i) zd[i] *= c[0];
  } else {
    const realtype* x0 = data(X[0]);
    for (sunindextype i = 0; i < n; ++i) zd[i] = c[0] * x0[i];
  }
  for (int k = 1; k < nvec; ++k) {
    const realtype* xd = data(X[k]);
    const realtype ck = c[k];
    for (sunindextype i = 0; i < n; ++i) zd[i] += ck * xd[i];
  }
  return 0;
}
// Z_k = a_k x + Y_k (Z_k may be Y_k)
inline int scale_add_multi(int nvec, realtype* a, N_Vector x, N_Vector* Y, N_Vector* Z) {
  const sunindextype n = length(x);
  const realtype* xd = data(x);
  for (int k = 0; k < nvec; ++k) {
    const realtype* yd = data(Y[k]);
    realtype* zd = data(Z[k]);
    const realtype ak = a[k];
    for (sunindextype i = 0; i < n; ++i) zd[i] = ak * xd[i] + yd[i];
  }
  return 0;
}
inline int dot_multi(int nvec, N_Vector x, N_Vector* Y, realtype* d) {
  for (int k = 0; k < nvec; ++k) d[k] = dot(x, Y[k]);
  return 0;
}
// the first entry of V_0 when V_0 … V_{nvec−1} lie one after the other in memory (as a pool's
// consecutive clones do: nvector_pool.hpp), else nullptr
inline realtype* contiguous(int nvec, N_Vector* V) {
  realtype* first = data(V[0]);
  const sunindextype n = length(V[0]);
  for (int k = 1; k < nvec; ++k)
    if (data(V[k]) != first + k * n || length(V[k]) != n) return nullptr;
  return first;
}
// Z_k = a X_k + b Y_k; one loop over all the entries when each array lies in one piece (CVODES'
// predictor calls this q(q+1)/2 times a step on the sensitivities' Nordsieck arrays: 2–4 % of the
// humanoid's forward-sensitivity runs against a loop per vector)
inline int linear_sum_array(int nvec, realtype a, N_Vector* X, realtype b, N_Vector* Y, N_Vector* Z) {
  const realtype *xd = contiguous(nvec, X), *yd = contiguous(nvec, Y);
  realtype* zd = contiguous(nvec, Z);
  if (xd && yd && zd && length(X[0]) == length(Z[0]) && length(Y[0]) == length(Z[0])) {
    const sunindextype n = nvec * length(Z[0]);
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
    return 0;
  }
  for (int k = 0; k < nvec; ++k) linear_sum(a, X[k], b, Y[k], Z[k]);
  return 0;
}
inline int scale_array(int nvec, realtype* c, N_Vector* X, N_Vector* Z) {
  for (int k = 0; k < nvec; ++k) scale(c[k], X[k], Z[k]);
  return 0;
}
inline int const_array(int nvec, realtype c, N_Vector* Z) {
  for (int k = 0; k < nvec; ++k) constant(c, Z[k]);
  return 0;
}
inline int wrms_norm_array(int nvec, N_Vector* X, N_Vector* W, realtype* m) {
  for (int k = 0; k < nvec; ++k) m[k] = wrms_norm(X[k], W[k]);
  return 0;
}
inline int wrms_norm_mask_array(int nvec, N_Vector* X, N_Vector* W, N_Vector id, realtype* m) {
  for (int k = 0; k < nvec; ++k) m[k] = wrms_norm_mask(X[k], W[k], id);
  return 0;
}
// Z[j][k] = a_j X_k + Y[j][k], j < nsum, k < nvec (Z[j][k] may be Y[j][k])
inline int scale_add_multi_array(int nvec, int nsum, realtype* a, N_Vector* X, N_Vector** Y, N_Vector** Z) {
  for (int k = 0; k < nvec; ++k) {
    const sunindextype n = length(X[k]);
    const realtype* xd = data(X[k]);
    for (int j = 0; j < nsum; ++j) {
      const realtype* yd = data(Y[j][k]);
      realtype* zd = data(Z[j][k]);
      const realtype aj = a[j];
      for (sunindextype i = 0; i < n; ++i) zd[i] = aj * xd[i] + yd[i];
    }
  }
  return 0;
}
// Z_k = Σ_j c_j X[j][k], k < nvec (Z may be X[0])
inline int linear_combination_array(int nvec, int nsum, realtype* c, N_Vector** X, N_Vector* Z) {
  for (int k = 0; k < nvec; ++k) {
    const sunindextype n = length(Z[k]);
    realtype* zd = data(Z[k]);
    if (X[0][k] == Z[k]) {
      if (c[0] != 1.0)
        for (sunindextype i = 0; i < n; ++i) zd[i] *= c[0];
    } else {
      const realtype* x0 = data(X[0][k]);
      for (sunindextype i = 0; i < n; ++i) zd[i] = c[0] * x0[i];
    }
    for (int j = 1; j < nsum; ++j) {
      const realtype* xd = data(X[j][k]);
      const realtype cj = c[j];
      for (sunindextype i = 0; i < n; ++i) zd[i] += cj * xd[i];
    }
  }
  return 0;
}

}  // namespace detail

// whether x_0 … x_{n−1} are all finite: no exponent of all ones, one OR over the bits (it
// vectorizes; Eigen's allFinite forms x − x and tests one entry at a time, ~45 % of the
// sensitivity right-hand side's own time with 100 columns)
inline bool all_finite(const realtype* x, sunindextype n) {
  constexpr std::uint64_t exponent = 0x7ff0000000000000ull;
  std::uint64_t bad = 0;
  for (sunindextype i = 0; i < n; ++i) {
    std::uint64_t bits;
    std::memcpy(&bits, x + i, sizeof bits);
    bad |= std::uint64_t((bits & exponent) == exponent);
  }
  return bad == 0;
}

// w = 1/(rtol·|y| + atol), entry by entry: CVODE's weights for scalar tolerances (cvEwtSetSS's
// |y|, ·rtol, +atol and 1/x, four passes over memory, in one), for CVodeWFtolerances.  CVODES'
// sensitivities under CVodeSensEEtolerances take their weights from the same function (on p̄ s)
inline void error_weights(realtype rtol, realtype atol, N_Vector y, N_Vector w) {
  const sunindextype n = detail::length(w);
  const realtype* yd = detail::data(y);
  realtype* wd = detail::data(w);
  for (sunindextype i = 0; i < n; ++i) wd[i] = 1.0 / (rtol * std::abs(yd[i]) + atol);
}

// Installs the loops above on a serial vector (with its fused and vector-array operations on);
// N_VClone copies the table, so every vector cloned from v has them too.
inline void install(N_Vector v) {
  N_Vector_Ops o = v->ops;
  o->nvlinearsum = detail::linear_sum;
  o->nvconst = detail::constant;
  o->nvprod = detail::prod;
  o->nvdiv = detail::div;
  o->nvscale = detail::scale;
  o->nvabs = detail::abs;
  o->nvinv = detail::inv;
  o->nvaddconst = detail::add_const;
  o->nvdotprod = detail::dot;
  o->nvmaxnorm = detail::max_norm;
  o->nvwrmsnorm = detail::wrms_norm;
  o->nvwrmsnormmask = detail::wrms_norm_mask;
  o->nvmin = detail::min;
  o->nvwl2norm = detail::wl2_norm;
  o->nvl1norm = detail::l1_norm;
  o->nvcompare = detail::compare;
  o->nvinvtest = detail::inv_test;
  o->nvlinearcombination = detail::linear_combination;
  o->nvscaleaddmulti = detail::scale_add_multi;
  o->nvdotprodmulti = detail::dot_multi;
  o->nvlinearsumvectorarray = detail::linear_sum_array;
  o->nvscalevectorarray = detail::scale_array;
  o->nvconstvectorarray = detail::const_array;
  o->nvwrmsnormvectorarray = detail::wrms_norm_array;
  o->nvwrmsnormmaskvectorarray = detail::wrms_norm_mask_array;
  o->nvscaleaddmultivectorarray = detail::scale_add_multi_array;
  o->nvlinearcombinationvectorarray = detail::linear_combination_array;
  o->nvdotprodlocal = detail::dot;
  o->nvmaxnormlocal = detail::max_norm;
  o->nvminlocal = detail::min;
  o->nvl1normlocal = detail::l1_norm;
  o->nvinvtestlocal = detail::inv_test;
  o->nvwsqrsumlocal = detail::wsqr_sum;
  o->nvwsqrsummasklocal = detail::wsqr_sum_mask;
  o->nvdotprodmultilocal = detail::dot_multi;
}

// V_0 … V_{nvec−1}, n entries each, as the columns of one n × nvec column-major block, for code that
// works on all of them at once (the sensitivities' right-hand side): the vectors' own entries when
// they lie in one piece, as a pool's consecutive clones do, else `scratch`, which load() fills from
// the vectors and store() writes back to them (both nothing in place)
class ColumnBlock {
 public:
  ColumnBlock(int nvec, N_Vector* V, sunindextype n, std::vector<realtype>& scratch) : nvec_(nvec), V_(V), n_(n) {
    realtype* first = detail::contiguous(nvec, V);
    if (first && detail::length(V[0]) == n) {
      data_ = first;
      return;
    }
    scratch.resize(static_cast<size_t>(n) * static_cast<size_t>(nvec));
    data_ = scratch.data();
    in_place_ = false;
  }
  realtype* data() const { return data_; }
  bool in_place() const { return in_place_; }
  void load() const {
    if (!in_place_)
      for (int k = 0; k < nvec_; ++k) std::copy_n(detail::data(V_[k]), n_, data_ + k * n_);
  }
  void store() const {
    if (!in_place_)
      for (int k = 0; k < nvec_; ++k) std::copy_n(data_ + k * n_, n_, detail::data(V_[k]));
  }

 private:
  int nvec_;
  N_Vector* V_;
  sunindextype n_;
  realtype* data_ = nullptr;
  bool in_place_ = true;
};

// A serial vector of length n with fused and vector-array operations, and the loops above
inline N_Vector new_vector(sunindextype n, SUNContext ctx) {
  N_Vector v = N_VNew_Serial(n, ctx);
  if (!v) return nullptr;
  N_VEnableFusedOps_Serial(v, SUNTRUE);
  install(v);
  return v;
}

}  // namespace soadyn::nvector_ops
