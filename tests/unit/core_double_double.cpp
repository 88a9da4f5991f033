#include <sysid/core/double_double.hpp>
#include <sysid/core/double_double_cholesky.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>
#include <vector>

#include "random_matrices.hpp"

namespace test_unit_core_double_double {

using namespace sysid;

namespace {

// The reference arithmetic: IEEE binary128 (113-bit significand), which holds
// the exact product of two doubles and double-double values exactly.
using quad = __float128;

quad as_quad(const DoubleDouble& x) { return static_cast<quad>(x.hi) + static_cast<quad>(x.lo); }

double relative(quad got, quad want) {
  const quad diff = got - want;
  const quad scale = want < 0 ? -want : want;
  return static_cast<double>((diff < 0 ? -diff : diff) / scale);
}

/// Random double-double with hi spread over several decades and lo a proper tail.
DoubleDouble random_double_double(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> mantissa(0.5, 1.0), sign(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-20, 20);
  const double hi = std::ldexp(mantissa(rng), exponent(rng)) * (sign(rng) < 0 ? -1.0 : 1.0);
  const double lo = hi * 1e-17 * sign(rng);
  return two_sum(hi, lo);
}

/// G = H^T H summed in binary128 and split into double-double; gq holds the
/// binary128 entries (column-major) for residual checks.
DoubleDoubleMatrix gram_in_binary128(const Eigen::MatrixXd& H, std::vector<quad>& gq) {
  const Eigen::Index k = H.cols();
  DoubleDoubleMatrix G{Eigen::MatrixXd(k, k), Eigen::MatrixXd(k, k)};
  gq.assign(static_cast<std::size_t>(k * k), 0);
  for (Eigen::Index i = 0; i < k; ++i)
    for (Eigen::Index j = 0; j < k; ++j) {
      quad s = 0;
      for (Eigen::Index r = 0; r < H.rows(); ++r) s += static_cast<quad>(H(r, i)) * static_cast<quad>(H(r, j));
      gq[static_cast<std::size_t>(j * k + i)] = s;
      const double hi = static_cast<double>(s);
      G.set(i, j, {hi, static_cast<double>(s - static_cast<quad>(hi))});
    }
  return G;
}

/// max |R^T R - G| over the entries, in binary128.
double gram_residual(const Eigen::MatrixXd& R, const std::vector<quad>& gq) {
  const Eigen::Index k = R.cols();
  double worst = 0;
  for (Eigen::Index i = 0; i < k; ++i)
    for (Eigen::Index j = 0; j < k; ++j) {
      quad s = 0;
      for (Eigen::Index r = 0; r < k; ++r) s += static_cast<quad>(R(r, i)) * static_cast<quad>(R(r, j));
      const quad d = s - gq[static_cast<std::size_t>(j * k + i)];
      worst = std::max(worst, static_cast<double>(d < 0 ? -d : d));
    }
  return worst;
}

}  // namespace

TEST(DoubleDouble, ErrorFreeTransformationsAreExact) {
  std::mt19937_64 rng(41);
  for (int k = 0; k < 20000; ++k) {
    const double a = random_double_double(rng).hi, b = random_double_double(rng).hi;
    // Both forms, whichever two_prod uses on this machine.
    for (const DoubleDouble p : {two_prod(a, b), two_prod_fma(a, b), two_prod_dekker(a, b)}) {
      EXPECT_TRUE(as_quad(p) == static_cast<quad>(a) * static_cast<quad>(b)) << a << " * " << b;
      EXPECT_EQ(p.hi, a * b);
    }
    const DoubleDouble s = two_sum(a, b);
    EXPECT_TRUE(as_quad(s) == static_cast<quad>(a) + static_cast<quad>(b)) << a << " + " << b;
    EXPECT_EQ(s.hi, a + b);
  }
}

TEST(DoubleDouble, OperationsAreAccurateToAFewUnitsOfTwoToTheMinus106) {
  // u^2 = 2^-106 = 1.2e-32; the bounds of Joldes, Muller & Popescu (2017) are a
  // few u^2 for +, * and /, and the Newton square root is of the same order.
  std::mt19937_64 rng(42);
  double worst_add = 0, worst_mul = 0, worst_div = 0, worst_sqrt = 0;
  for (int k = 0; k < 20000; ++k) {
    const DoubleDouble x = random_double_double(rng), y = random_double_double(rng);
    const quad qx = as_quad(x), qy = as_quad(y);
    if (qx + qy != 0) worst_add = std::max(worst_add, relative(as_quad(x + y), qx + qy));
    worst_mul = std::max(worst_mul, relative(as_quad(x * y), qx * qy));
    worst_div = std::max(worst_div, relative(as_quad(x / y), qx / qy));
    const DoubleDouble ax = x.hi < 0 ? -x : x;
    const DoubleDouble r = sqrt(ax);
    worst_sqrt = std::max(worst_sqrt, relative(as_quad(r) * as_quad(r), as_quad(ax)));
  }
  const double u2 = std::ldexp(1.0, -106);
  EXPECT_LT(worst_add, 3 * u2);
  EXPECT_LT(worst_mul, 7 * u2);
  EXPECT_LT(worst_div, 16 * u2);
  EXPECT_LT(worst_sqrt, 8 * u2);  // relative error of r^2, twice that of r
  EXPECT_EQ(sqrt(DoubleDouble(0.0)).hi, 0.0);
  EXPECT_TRUE(std::isnan(sqrt(DoubleDouble(-1.0)).hi));
}

TEST(DoubleDouble, DotProductIsAccurateToTheOrderOfNTimesTwoToTheMinus106OfItsTerms) {
  // Against binary128 sums of the exact products: error <= (n + 4) u^2 sum |x y|
  // (file comment of dot), for lengths around the four partial sums, with
  // terms that cancel to a small fraction of their sum.
  std::mt19937_64 rng(43);
  const double u2 = std::ldexp(1.0, -106);
  double worst = 0;
  for (Eigen::Index n : {0, 1, 2, 3, 4, 5, 7, 8, 9, 33, 80, 257}) {
    for (int trial = 0; trial < 50; ++trial) {
      std::vector<DoubleDouble> x(static_cast<std::size_t>(n)), y(static_cast<std::size_t>(n));
      quad exact = 0, magnitude = 0;
      for (std::size_t p = 0; p < x.size(); ++p) {
        x[p] = random_double_double(rng);
        y[p] = random_double_double(rng);
        const quad term = as_quad(x[p]) * as_quad(y[p]);
        exact += term;
        magnitude += term < 0 ? -term : term;
      }
      if (n > 1 && trial % 2 == 1) {  // cancel most of the sum: the last term takes it back
        quad rest = 0;  // summed afresh: exact minus the old last term would carry its rounding
        for (std::size_t p = 0; p + 1 < x.size(); ++p) rest += as_quad(x[p]) * as_quad(y[p]);
        const double target = -static_cast<double>(rest / as_quad(y.back())) * (1.0 + 1e-9);
        x.back() = DoubleDouble(target);
        exact = rest + as_quad(x.back()) * as_quad(y.back());
        magnitude = 0;
        for (std::size_t p = 0; p < x.size(); ++p) {
          const quad term = as_quad(x[p]) * as_quad(y[p]);
          magnitude += term < 0 ? -term : term;
        }
      }
      const DoubleDouble got = dot(x.data(), y.data(), n);
      if (n == 0) {
        EXPECT_EQ(got.hi, 0.0);
        continue;
      }
      const quad diff = as_quad(got) - exact;
      const double error = static_cast<double>((diff < 0 ? -diff : diff) / magnitude);
      EXPECT_LE(error, static_cast<double>(n + 4) * u2) << "n = " << n << ", trial " << trial;
      worst = std::max(worst, error / (static_cast<double>(n + 4) * u2));
    }
  }
  std::cout << "dot: worst error / ((n + 4) u^2 sum |x y|) = " << worst << "\n";
}

TEST(DoubleDoubleCholesky, FactorsAGramMatrixThatDoubleCannot) {
  // H with singular values 1 .. 1e-11 (cond(G) = 1e22 > 1 / u): Eigen's LLT
  // of the Gram matrix rounded to double fails or is far off; the double-double
  // factor reproduces G to ~1e-30 of its norm.
  std::mt19937_64 rng(7);
  const Eigen::Index rows = 60, k = 12;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qu(test::randn(rng, rows, k)), qv(test::randn(rng, k, k));
  const Eigen::MatrixXd U = qu.householderQ() * Eigen::MatrixXd::Identity(rows, k);
  const Eigen::MatrixXd V = qv.householderQ() * Eigen::MatrixXd::Identity(k, k);
  Eigen::VectorXd sv(k);
  for (Eigen::Index i = 0; i < k; ++i) sv(i) = std::pow(10.0, -11.0 * static_cast<double>(i) / static_cast<double>(k - 1));
  const Eigen::MatrixXd H = U * sv.asDiagonal() * V.transpose();
  // G = H^T H exactly enough: every entry summed in binary128, then split.
  std::vector<quad> gq;
  const DoubleDoubleMatrix G = gram_in_binary128(H, gq);
  const DoubleDoubleCholeskyResult chol = double_double_cholesky(G);
  ASSERT_TRUE(chol.positive_definite);
  EXPECT_TRUE(chol.R.isUpperTriangular());
  EXPECT_GT(chol.smallest_pivot_ratio, 1e-12);  // >= sigma_min / sigma_max = 1e-11 up to rounding
  EXPECT_LE(chol.smallest_pivot_ratio, 1.0);
  // Residual of R^T R against G, relative to ||G|| ~ 1, in binary128. R is
  // rounded to double, so the bound is that of a double R: ~u ||G||.
  const double worst = gram_residual(chol.R, gq);
  EXPECT_LT(worst, 1e-15);
  // The small end: R's singular values are H's (to ~u of each, far better than
  // the u ||H|| of any double factorisation), while double's LLT cannot deliver them.
  const Eigen::VectorXd r_sv = Eigen::JacobiSVD<Eigen::MatrixXd>(chol.R).singularValues();
  for (Eigen::Index i = 0; i < k; ++i) EXPECT_NEAR(r_sv(i) / sv(i), 1.0, 1e-4) << "singular value " << i;
  const Eigen::LLT<Eigen::MatrixXd> plain(G.hi);
  if (plain.info() == Eigen::Success) {
    const Eigen::MatrixXd Rd = plain.matrixU();
    const Eigen::VectorXd d_sv = Eigen::JacobiSVD<Eigen::MatrixXd>(Rd).singularValues();
    EXPECT_GT(std::abs(d_sv(k - 1) / sv(k - 1) - 1.0), 1e-2) << "the case does not need double-double";
  }
}

TEST(DoubleDoubleCholesky, ReportsASingularMatrix) {
  // Two equal rows and columns: the third pivot is zero up to double-double rounding, of either sign.
  const Eigen::MatrixXd h = test::white_noise(50, 4, 3);
  Eigen::MatrixXd g = h.transpose() * h;
  g.row(2) = g.row(1);  // exactly, not up to the rounding of two dot products
  g.col(2) = g.col(1);
  const DoubleDoubleCholeskyResult chol = double_double_cholesky({g, Eigen::MatrixXd::Zero(4, 4)});
  EXPECT_TRUE(!chol.positive_definite || chol.smallest_pivot_ratio < 1e-14) << chol.smallest_pivot_ratio;
  const DoubleDoubleCholeskyResult negative = double_double_cholesky({-Eigen::MatrixXd::Identity(3, 3), Eigen::MatrixXd::Zero(3, 3)});
  EXPECT_FALSE(negative.positive_definite);
}

TEST(DoubleDoubleCholesky, SemidefiniteModeZeroesAPivotTheRoundingOfGExplains) {
  // Column 3 of H is a combination of columns 0 and 1 with large coefficients
  // (rounded to double: dependent to ~1e-16 of its norm), as near common factors
  // make a polynomial model's Jacobian. Its Schur complement pivot is at the
  // rounding level, of either sign.
  const Eigen::MatrixXd base = test::white_noise(80, 5, 11);
  Eigen::MatrixXd H = base;
  H.col(3) = 1e3 * base.col(0) - 2e3 * base.col(1);
  std::vector<quad> gq;
  const DoubleDoubleMatrix G = gram_in_binary128(H, gq);
  const DoubleDoubleCholeskyResult plain = double_double_cholesky(G);
  EXPECT_TRUE(!plain.factorised || plain.smallest_pivot_ratio < kRankDeficientPivotRatio) << plain.smallest_pivot_ratio;

  DoubleDoubleCholeskyOptions semidefinite;
  semidefinite.gram_relative_error = kDoubleDoubleGramRelativeError;
  const DoubleDoubleCholeskyResult chol = double_double_cholesky(G, semidefinite);
  ASSERT_TRUE(chol.factorised);
  EXPECT_FALSE(chol.positive_definite);
  ASSERT_EQ(chol.zero_pivots, std::vector<Eigen::Index>{3});
  EXPECT_LE(chol.largest_zeroed_pivot_to_bound, 1.0);
  EXPECT_TRUE(chol.R.isUpperTriangular());
  EXPECT_EQ(chol.R.row(3).cwiseAbs().maxCoeff(), 0.0);
  // R^T R is G (relative to its largest entry) and R's column norms are H's.
  EXPECT_LT(gram_residual(chol.R, gq) / G.hi.cwiseAbs().maxCoeff(), 1e-15);
  for (Eigen::Index j = 0; j < 5; ++j)
    EXPECT_NEAR(chol.R.col(j).norm() / H.col(j).norm(), 1.0, 1e-14) << "column " << j;
  // The other columns factorise as if column 3 were absent: R of H without it.
  Eigen::MatrixXd reduced(80, 4);
  reduced << base.leftCols(3), base.col(4);
  std::vector<quad> gr;
  const DoubleDoubleCholeskyResult without = double_double_cholesky(gram_in_binary128(reduced, gr));
  ASSERT_TRUE(without.positive_definite);
  const std::vector<Eigen::Index> kept{0, 1, 2, 4};
  for (std::size_t a = 0; a < kept.size(); ++a)
    for (std::size_t b = a; b < kept.size(); ++b)
      EXPECT_NEAR(chol.R(kept[a], kept[b]), without.R(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)), 1e-12)
          << a << ", " << b;
}

TEST(DoubleDoubleCholesky, SemidefiniteModeStillRejectsAnIndefiniteMatrix) {
  // [[1, 2], [2, 1]] has the pivot 1 - 4 = -3: no rounding of a Gram matrix explains it.
  Eigen::MatrixXd g(2, 2);
  g << 1, 2, 2, 1;
  DoubleDoubleCholeskyOptions semidefinite;
  semidefinite.gram_relative_error = kDoubleDoubleGramRelativeError;
  const DoubleDoubleCholeskyResult chol = double_double_cholesky({g, Eigen::MatrixXd::Zero(2, 2)}, semidefinite);
  EXPECT_FALSE(chol.factorised);
  EXPECT_FALSE(chol.positive_definite);
  // A positive definite matrix factorises exactly as without the mode.
  const Eigen::MatrixXd h = test::white_noise(30, 4, 5);
  std::vector<quad> gq;
  const DoubleDoubleMatrix G = gram_in_binary128(h, gq);
  const DoubleDoubleCholeskyResult definite = double_double_cholesky(G, semidefinite);
  ASSERT_TRUE(definite.positive_definite);
  EXPECT_TRUE(definite.zero_pivots.empty());
  EXPECT_EQ(definite.R, double_double_cholesky(G).R);
}

}  // namespace test_unit_core_double_double
