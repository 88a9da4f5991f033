// The innovation-form state space of polynomial models
// (pem/polynomial_model.hpp): its input and noise transfer functions equal the
// polynomial ratios, for the common-denominator (ARMAX) and the separate-block
// (OE / Box-Jenkins) realisations, and several outputs stack.
#include <sysid/core/frequency_response.hpp>
#include <sysid/pem/polynomial_model.hpp>

#include <gtest/gtest.h>

#include <complex>
#include <numbers>

namespace test_unit_pem_polynomial_model {

using namespace sysid;

namespace {

/// p(q^-1) at z = exp(i w): sum_k p_k z^-k.
std::complex<double> eval(const Eigen::VectorXd& p, std::complex<double> z, int delay = 0) {
  std::complex<double> s = 0;
  for (Eigen::Index k = 0; k < p.size(); ++k) s += p(k) * std::pow(z, -static_cast<double>(k + delay));
  return s;
}

/// Checks G_i = B_i q^-nk_i / (A F_i) and H = C / (A D) against the state space at a few frequencies.
void expect_equivalent(const PolynomialModel& pm) {
  const InnovationStateSpace ss = to_innovation_state_space(pm);
  const Eigen::Index m = pm.inputs();
  StateSpace noise(ss.model.A, ss.K, ss.model.C, Eigen::MatrixXd::Ones(1, 1), pm.Ts);
  for (double f : {0.01, 0.07, 0.2, 0.41}) {
    const std::complex<double> z = std::polar(1.0, 2 * std::numbers::pi * f * pm.Ts);
    const Eigen::VectorXd freq = Eigen::VectorXd::Constant(1, f);
    if (m > 0) {
      const Eigen::MatrixXcd g = frequency_response(ss.model, freq).front();
      for (Eigen::Index i = 0; i < m; ++i) {
        const auto k = static_cast<std::size_t>(i);
        const std::complex<double> expected = eval(pm.B[k], z, pm.nk[k]) / (eval(pm.A, z) * eval(pm.F[k], z));
        EXPECT_LT(std::abs(g(0, i) - expected), 1e-10 * (1 + std::abs(expected))) << "input " << i << " f " << f;
      }
    }
    const std::complex<double> h = frequency_response(noise, freq).front()(0, 0);
    const std::complex<double> expected = eval(pm.C, z) / (eval(pm.A, z) * eval(pm.D, z));
    EXPECT_LT(std::abs(h - expected), 1e-10 * (1 + std::abs(expected))) << "noise f " << f;
  }
}

PolynomialModel armax_example() {
  PolynomialModel pm;
  pm.Ts = 1.0;
  pm.A = Eigen::Vector3d(1.0, -1.5, 0.7);
  pm.B = {Eigen::Vector2d(1.0, 0.5), Eigen::Vector3d(0.2, -0.1, 0.05)};
  pm.nk = {1, 3};
  pm.F = {Eigen::VectorXd::Ones(1), Eigen::VectorXd::Ones(1)};
  pm.C = Eigen::Vector2d(1.0, 0.4);
  return pm;
}

}  // namespace

TEST(PolynomialModel, ArmaxUsesOneCommonDenominator) {
  const PolynomialModel pm = armax_example();
  // n = max(na, nk_i + nb_i - 1, nc) = max(2, 1 + 2 - 1, 3 + 3 - 1, 1)
  EXPECT_EQ(to_innovation_state_space(pm).model.order(), 5);
  expect_equivalent(pm);
}

TEST(PolynomialModel, OutputErrorAndBoxJenkinsUseSeparateBlocks) {
  PolynomialModel pm = armax_example();
  pm.A = Eigen::VectorXd::Ones(1);
  pm.C = Eigen::VectorXd::Ones(1);
  pm.F = {Eigen::Vector3d(1.0, -1.2, 0.6), Eigen::Vector2d(1.0, -0.3)};
  expect_equivalent(pm);
  EXPECT_EQ(to_innovation_state_space(pm).K.norm(), 0.0);  // OE: no noise model
  pm.C = Eigen::Vector2d(1.0, 0.3);
  pm.D = Eigen::Vector2d(1.0, -0.8);
  expect_equivalent(pm);
}

TEST(PolynomialModel, TimeSeriesModelHasNoInputs) {
  PolynomialModel pm;
  pm.A = Eigen::Vector3d(1.0, -0.9, 0.5);
  pm.C = Eigen::Vector2d(1.0, 0.5);
  const InnovationStateSpace ss = to_innovation_state_space(pm);
  EXPECT_EQ(ss.model.inputs(), 0);
  expect_equivalent(pm);
}

TEST(PolynomialModel, OutputsStackBlockDiagonally) {
  PolynomialModel second = armax_example();
  second.A = Eigen::Vector2d(1.0, -0.5);
  const InnovationStateSpace both = to_innovation_state_space(std::vector<PolynomialModel>{armax_example(), second});
  EXPECT_EQ(both.model.outputs(), 2);
  EXPECT_EQ(both.model.order(), to_innovation_state_space(armax_example()).model.order() + to_innovation_state_space(second).model.order());
  const Eigen::MatrixXcd g = frequency_response(both.model, Eigen::VectorXd::Constant(1, 0.1)).front();
  const Eigen::MatrixXcd g2 = frequency_response(to_innovation_state_space(second).model, Eigen::VectorXd::Constant(1, 0.1)).front();
  EXPECT_LT(std::abs(g(1, 1) - g2(0, 1)), 1e-12);
}

TEST(PolynomialModel, InvalidModelsAreRejected) {
  PolynomialModel pm = armax_example();
  pm.A(0) = 2.0;
  EXPECT_THROW(to_innovation_state_space(pm), std::invalid_argument);
  pm = armax_example();
  pm.nk = {1};
  EXPECT_THROW(to_innovation_state_space(pm), std::invalid_argument);
  pm = armax_example();
  pm.nk = {-1, 0};
  EXPECT_THROW(to_innovation_state_space(pm), std::invalid_argument);
}

}  // namespace test_unit_pem_polynomial_model
