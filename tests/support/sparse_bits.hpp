#pragma once
// Bit-exact comparison of doubles and sparse matrices, for the round-trip tests
// of the file readers and writers.
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <cstdint>
#include <cstring>

namespace sysid::test {

using Sparse = Eigen::SparseMatrix<double>;

inline std::uint64_t bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

/// Same shape, same stored pattern (explicit zeros included) and the same bits in
/// every stored value: what "bit-exact round trip" means for a sparse matrix.
inline ::testing::AssertionResult identical(Sparse a, Sparse b) {
  a.makeCompressed();
  b.makeCompressed();
  if (a.rows() != b.rows() || a.cols() != b.cols())
    return ::testing::AssertionFailure() << "shape " << a.rows() << "x" << a.cols() << " vs " << b.rows() << "x"
                                         << b.cols();
  if (a.nonZeros() != b.nonZeros())
    return ::testing::AssertionFailure() << "stored entries " << a.nonZeros() << " vs " << b.nonZeros();
  for (Eigen::Index k = 0; k <= a.outerSize(); ++k)
    if (a.outerIndexPtr()[k] != b.outerIndexPtr()[k]) return ::testing::AssertionFailure() << "column start " << k;
  for (Eigen::Index k = 0; k < a.nonZeros(); ++k) {
    if (a.innerIndexPtr()[k] != b.innerIndexPtr()[k]) return ::testing::AssertionFailure() << "row index of entry " << k;
    if (bits(a.valuePtr()[k]) != bits(b.valuePtr()[k]))
      return ::testing::AssertionFailure() << "entry " << k << ": " << a.valuePtr()[k] << " vs " << b.valuePtr()[k];
  }
  return ::testing::AssertionSuccess();
}

}  // namespace sysid::test
