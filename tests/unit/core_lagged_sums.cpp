#include <sysid/core/detail/lagged_sums.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "random_matrices.hpp"

namespace test_unit_core_lagged_sums {

using namespace sysid;

namespace {

// Reference arithmetic: IEEE binary128 holds every product of two doubles exactly.
using quad = __float128;

quad as_quad(const DoubleDouble& x) { return static_cast<quad>(x.hi) + static_cast<quad>(x.lo); }
double magnitude(quad x) { return static_cast<double>(x < 0 ? -x : x); }

}  // namespace

TEST(LaggedSums, CorrelationInDoubleDoubleSurvivesCancellation) {
  // sum_t x(t) y(t+q) over 100 000 samples where y is 1 + 1e-13 noise and x
  // comes in pairs x, -x: each pair cancels to 1e-13 of its terms, and the
  // sum is ~4e-16 of sum |x y|. Double keeps about three digits of it,
  // double-double (error ~1e-28 of sum |x y|) more than ten.
  const Eigen::Index n = 100000, lags = 7;
  const Eigen::MatrixXd w = test::white_noise(n + lags, 2, 5);
  Eigen::VectorXd x = w.col(0);
  const Eigen::VectorXd y = Eigen::VectorXd::Ones(n + lags) + 1e-13 * w.col(1);
  for (Eigen::Index t = 0; t < n; t += 2) x(t + 1) = -x(t);
  std::vector<DoubleDouble> got(lags);
  detail::correlate_double_double(x.data(), y.data(), n, lags, got.data());
  for (Eigen::Index q = 0; q < lags; ++q) {
    quad exact = 0, magnitude = 0;
    double plain = 0;
    for (Eigen::Index t = 0; t < n; ++t) {
      const quad p = static_cast<quad>(x(t)) * static_cast<quad>(y(t + q));
      exact += p;
      magnitude += p < 0 ? -p : p;
      plain += x(t) * y(t + q);
    }
    const quad error = as_quad(got[static_cast<std::size_t>(q)]) - exact;
    const double abs_error = static_cast<double>(error < 0 ? -error : error);
    const double abs_exact = std::abs(static_cast<double>(exact));
    EXPECT_LT(abs_error / static_cast<double>(magnitude), 1e-28) << "lag " << q;
    EXPECT_LT(abs_error / abs_exact, 1e-10) << "lag " << q;
    EXPECT_GT(std::abs(plain - static_cast<double>(exact)) / abs_exact, 1e-6)
        << "lag " << q << ": the case does not need double-double";
  }
}

TEST(LaggedSums, CorrelationKernelsGiveTheSameBitsForEveryLagCount) {
  // The run-time choice of kernel (FMA or Dekker's product; vector widths) and
  // the number of lags asked for must not change a single bit of any lag:
  // models are reproducible across machines. Lengths cross the 256-term blocks.
  const Eigen::MatrixXd w = test::white_noise(1300, 2, 11);
  for (const Eigen::Index count : {Eigen::Index{1}, Eigen::Index{255}, Eigen::Index{257}, Eigen::Index{1200}})
    for (const Eigen::Index lags : {Eigen::Index{1}, Eigen::Index{3}, Eigen::Index{5}, Eigen::Index{8}, Eigen::Index{21},
                                     Eigen::Index{29}, Eigen::Index{66}}) {
      std::vector<DoubleDouble> all(static_cast<std::size_t>(lags)), portable(all.size());
      detail::correlate_double_double(w.col(0).data(), w.col(1).data(), count, lags, all.data());
      detail::correlate_double_double_without_fma(w.col(0).data(), w.col(1).data(), count, lags, portable.data());
      for (Eigen::Index q = 0; q < lags; ++q) {
        DoubleDouble one;
        detail::correlate_double_double(w.col(0).data(), w.col(1).data() + q, count, 1, &one);
        const DoubleDouble& got = all[static_cast<std::size_t>(q)];
        const DoubleDouble& dekker = portable[static_cast<std::size_t>(q)];
        EXPECT_EQ(got.hi, one.hi) << "count " << count << " lags " << lags << " lag " << q;
        EXPECT_EQ(got.lo, one.lo) << "count " << count << " lags " << lags << " lag " << q;
        EXPECT_EQ(got.hi, dekker.hi) << "count " << count << " lags " << lags << " lag " << q;
        EXPECT_EQ(got.lo, dekker.lo) << "count " << count << " lags " << lags << " lag " << q;
      }
    }
}

TEST(LaggedSums, DoubleDoubleAgreesWithDoubleOnWellConditionedData) {
  const Eigen::MatrixXd x = test::white_noise(500, 2, 1), y = test::white_noise(500, 3, 2);
  const Eigen::Index i2 = 6, j = 500 - i2 + 1;
  for (bool symmetric : {false, true}) {
    const Eigen::MatrixXd& other = symmetric ? x : y;
    const Eigen::MatrixXd plain = detail::lagged_sums(x, other, i2, j, symmetric);
    const DoubleDoubleMatrix dd = detail::lagged_sums_double_double(x, other, i2, j, symmetric);
    EXPECT_LT((dd.hi - plain).norm(), 1e-13 * plain.norm()) << "symmetric " << symmetric;
  }
}

TEST(LaggedSums, ShiftedColumnsGramIsTheExplicitGramMatrix) {
  // Three signals whose shifted copies make a prediction-error-like Jacobian
  // (shift ranges 1..5, 0..4 with sign -1, 1..3) plus an unshifted column,
  // against the explicit matrix's Gram matrix summed in binary128.
  const Eigen::Index n = 300;
  const Eigen::MatrixXd w = test::white_noise(n, 3, 9);
  const std::vector<Eigen::VectorXd> signals{w.col(0), 1e3 * w.col(1), 1e-3 * w.col(2)};
  std::vector<detail::ShiftedColumn> columns;
  for (Eigen::Index k = 1; k <= 5; ++k) columns.push_back({0, k, 1.0});
  for (Eigen::Index k = 0; k <= 4; ++k) columns.push_back({1, k, -1.0});
  for (Eigen::Index k = 1; k <= 3; ++k) columns.push_back({2, k, 1.0});
  columns.push_back({0, 0, 1.0});
  const auto p = static_cast<Eigen::Index>(columns.size());
  Eigen::MatrixXd explicit_matrix = Eigen::MatrixXd::Zero(n, p);
  for (Eigen::Index c = 0; c < p; ++c) {
    const detail::ShiftedColumn& col = columns[static_cast<std::size_t>(c)];
    explicit_matrix.col(c).tail(n - col.shift) = col.sign * signals[col.signal].head(n - col.shift);
  }
  const DoubleDoubleMatrix gram = detail::shifted_columns_gram_double_double(signals, columns);
  for (Eigen::Index a = 0; a < p; ++a)
    for (Eigen::Index b = 0; b < p; ++b) {
      quad exact = 0, scale = 0;
      for (Eigen::Index t = 0; t < n; ++t) {
        const quad prod = static_cast<quad>(explicit_matrix(t, a)) * static_cast<quad>(explicit_matrix(t, b));
        exact += prod;
        scale += prod < 0 ? -prod : prod;
      }
      EXPECT_LT(magnitude(as_quad(gram(a, b)) - exact) / static_cast<double>(scale), 1e-28) << a << ", " << b;
    }
}

TEST(LaggedSums, TableTakesTheKnownPairsItNeedsAndFormsTheRest) {
  // PEM's projection forms the lagged sums of y / C and u / C (shifts 0..6 and
  // 0..4); the Jacobian at the same C needs them over 1..6 and 0..4 beside new
  // signals. A table built with the projection's as `known` must be the table
  // built from scratch, bit for bit; a known table that does not cover a pair
  // (shorter shift range) must not be used for it.
  const Eigen::MatrixXd w = test::white_noise(400, 3, 21);
  const std::vector<Eigen::VectorXd> first{w.col(0), w.col(1)}, all{w.col(0), w.col(1), w.col(2)};
  std::vector<detail::ShiftedColumn> projection, jacobian, short_range;
  for (Eigen::Index k = 0; k <= 6; ++k) projection.push_back({0, k, -1.0});
  for (Eigen::Index k = 0; k <= 4; ++k) projection.push_back({1, k, 1.0});
  for (Eigen::Index k = 1; k <= 6; ++k) jacobian.push_back({0, k, 1.0});
  for (Eigen::Index k = 0; k <= 4; ++k) jacobian.push_back({1, k, -1.0});
  for (Eigen::Index k = 1; k <= 3; ++k) jacobian.push_back({2, k, -1.0});
  for (Eigen::Index k = 0; k <= 2; ++k) short_range.push_back({0, k, 1.0});
  short_range.push_back({1, 0, 1.0});
  const detail::LaggedSumsTable known = detail::lagged_sums_table(first, projection);
  EXPECT_TRUE(known.covers(0, 1, 1, 6, 0, 4));
  EXPECT_FALSE(known.covers(0, 2, 1, 6, 1, 3));  // no third signal in it
  const DoubleDoubleMatrix fresh = detail::shifted_columns_gram_double_double(all, jacobian);
  for (const auto* given : {&known, static_cast<const detail::LaggedSumsTable*>(nullptr)}) {
    const DoubleDoubleMatrix reused = detail::shifted_columns_gram(detail::lagged_sums_table(all, jacobian, given), jacobian);
    EXPECT_EQ(reused.hi, fresh.hi);
    EXPECT_EQ(reused.lo, fresh.lo);
  }
  const detail::LaggedSumsTable too_short = detail::lagged_sums_table(first, short_range);
  EXPECT_FALSE(too_short.covers(0, 0, 1, 6, 1, 6));
  const DoubleDoubleMatrix from_short =
      detail::shifted_columns_gram(detail::lagged_sums_table(all, jacobian, &too_short), jacobian);
  EXPECT_EQ(from_short.hi, fresh.hi);
  EXPECT_EQ(from_short.lo, fresh.lo);
}

TEST(LaggedSums, ShiftedColumnsGramRejectsInconsistentInput) {
  const std::vector<Eigen::VectorXd> signals{Eigen::VectorXd::Ones(10), Eigen::VectorXd::Ones(9)};
  EXPECT_THROW(detail::shifted_columns_gram_double_double(signals, {{0, 1, 1.0}}), std::invalid_argument);  // unequal lengths
  const std::vector<Eigen::VectorXd> one{Eigen::VectorXd::Ones(10)};
  EXPECT_THROW(detail::shifted_columns_gram_double_double(one, {{1, 0, 1.0}}), std::invalid_argument);   // no such signal
  EXPECT_THROW(detail::shifted_columns_gram_double_double(one, {{0, 10, 1.0}}), std::invalid_argument);  // shift >= n
  EXPECT_THROW(detail::shifted_columns_gram_double_double(one, {{0, -1, 1.0}}), std::invalid_argument);  // negative shift
}

}  // namespace test_unit_core_lagged_sums
