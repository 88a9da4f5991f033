// Tests of pem/residual_whiteness.hpp: the one-step residual of the true model is
// white, that of a least-squares AR fitted to a record with sensor noise is not;
// ARMA residuals are filtered by 1/C; experiments are pooled; a record too short
// to test gives no test.
#include <sysid/pem/arx.hpp>
#include <sysid/pem/residual_whiteness.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "par2_disturbance_polynomial.hpp"
#include "random_systems.hpp"

namespace test_unit_pem_residual_whiteness {

using namespace sysid;

namespace {

PolynomialModel time_series(const Eigen::VectorXd& a, const Eigen::VectorXd& c) {
  PolynomialModel m;
  m.A = a;
  m.C = c;
  m.noise_variance = 1.0;
  m.Ts = 5e-4;
  return m;
}

Eigen::VectorXd ar_process(const Eigen::VectorXd& a, Eigen::Index n, unsigned seed) {
  return filter_polynomial(Eigen::VectorXd::Ones(1), a, test::white_noise(n, 1, seed)).col(0);
}

IoData series(const Eigen::VectorXd& y) { return IoData(Eigen::MatrixXd(y.size(), 0), y, 5e-4); }

}  // namespace

TEST(ResidualWhiteness, TheTrueModelLeavesWhiteResiduals) {
  const Eigen::VectorXd a = test::par2_disturbance_denominator();
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const auto test = one_step_residual_whiteness(time_series(a, Eigen::VectorXd::Ones(1)), series(ar_process(a, 40000, seed)), 0, 0.0);
    ASSERT_TRUE(test.has_value());
    EXPECT_EQ(test->lags, 50);
    EXPECT_EQ(test->degrees_of_freedom, 46.0);
    EXPECT_EQ(test->samples, 40000 - 4);
    EXPECT_GT(test->p_value, 1e-3) << "seed " << seed;
  }
}

TEST(ResidualWhiteness, SensorNoiseLeavesCorrelationInTheLeastSquaresResiduals) {
  // 0.5 % of the process RMS, white: the least-squares AR(8) cannot reach the
  // ARMA(4, 4) innovations, and its residual keeps the resonances' correlation.
  const Eigen::VectorXd x = ar_process(test::par2_disturbance_denominator(), 40000, 4);
  const double rms = std::sqrt(x.squaredNorm() / static_cast<double>(x.size()));
  const IoData noisy = series(x + 0.005 * rms * test::white_noise(x.size(), 1, 5).col(0));
  const PolynomialModel ls = ar(noisy, {.na = 8}).models.front();
  const auto test = one_step_residual_whiteness(ls, noisy, 0, noisy.experiments[0].y.mean());
  ASSERT_TRUE(test.has_value());
  EXPECT_LT(test->p_value, 1e-12) << "Q " << test->statistic;
}

TEST(ResidualWhiteness, ArmaResidualsAreFilteredByTheNoiseModel) {
  // y = C/A e: with C the residual is white, without it (an AR read of an ARMA) it is not.
  Eigen::VectorXd a(3), c(2);
  a << 1.0, -1.5, 0.7;
  c << 1.0, 0.8;
  const Eigen::VectorXd y = filter_polynomial(c, a, test::white_noise(20000, 1, 6)).col(0);
  const auto with_c = one_step_residual_whiteness(time_series(a, c), series(y), 0, 0.0);
  const auto without_c = one_step_residual_whiteness(time_series(a, Eigen::VectorXd::Ones(1)), series(y), 0, 0.0);
  ASSERT_TRUE(with_c && without_c);
  EXPECT_GT(with_c->p_value, 1e-3);
  EXPECT_LT(without_c->p_value, 1e-12);
  EXPECT_EQ(with_c->degrees_of_freedom, 50.0 - 3.0);
}

TEST(ResidualWhiteness, ExperimentsArePooled) {
  const Eigen::VectorXd a = test::par2_disturbance_denominator();
  IoData data = series(ar_process(a, 20000, 7));
  data.experiments.push_back(series(ar_process(a, 10000, 8)).experiments.front());
  const auto test = one_step_residual_whiteness(time_series(a, Eigen::VectorXd::Ones(1)), data, 0, 0.0);
  ASSERT_TRUE(test.has_value());
  EXPECT_EQ(test->samples, 20000 - 4 + 10000 - 4);
  EXPECT_GT(test->p_value, 1e-3);
}

TEST(ResidualWhiteness, TooShortARecordGivesNoTestAndInputsAreRefused) {
  Eigen::VectorXd a = Eigen::VectorXd::Zero(9);
  a(0) = 1.0;
  a(1) = -0.5;
  EXPECT_FALSE(one_step_residual_whiteness(time_series(a, Eigen::VectorXd::Ones(1)), series(ar_process(a, 30, 9)), 0, 0.0));
  PolynomialModel with_input = time_series(test::par2_disturbance_denominator(), Eigen::VectorXd::Ones(1));
  with_input.B.push_back(Eigen::VectorXd::Ones(1));
  with_input.nk.push_back(1);
  with_input.F.push_back(Eigen::VectorXd::Ones(1));
  EXPECT_THROW(one_step_residual_whiteness(with_input, series(ar_process(a, 1000, 9)), 0, 0.0), std::invalid_argument);
}

}  // namespace test_unit_pem_residual_whiteness
