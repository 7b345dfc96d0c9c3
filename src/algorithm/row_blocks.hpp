// The kernels that take their right-hand sides as the rows of fixed-size blocks
// (articulated_solve.cpp, derivative_products.cpp): up to kMaxRows at a time, a column of a block
// then two AVX-512 registers; a narrower group in the fewest rows of 4, 8, 12 or 16 that hold it
// (zero-padded), so that 10 right-hand sides cost 12 rows, not 16; one alone in one row.
#pragma once

#include <Eigen/Core>

namespace soadyn::detail {

constexpr int kMaxRows = 16;

// an R-row block of C columns (at most MaxC), column-major; row-major when it is one row, as Eigen
// requires of a row vector (the same memory either way)
template <int R, int C, int MaxC = C>
using RowBlock = Eigen::Matrix<double, R, C, (R == 1 && C != 1) ? Eigen::RowMajor : Eigen::ColMajor, R, MaxC>;

// f.template operator()<R>() with R the rows for a group of 1 ≤ n ≤ kMaxRows right-hand sides
template <class F>
void with_rows(int n, F&& f) {
  if (n == 1)
    f.template operator()<1>();
  else if (n <= 4)
    f.template operator()<4>();
  else if (n <= 8)
    f.template operator()<8>();
  else if (n <= 12)
    f.template operator()<12>();
  else
    f.template operator()<16>();
}

}  // namespace soadyn::detail
