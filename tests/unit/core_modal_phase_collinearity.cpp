// Tests for include/sysid/core/modal_phase_collinearity.hpp: the collinearity of
// real, complex and mixed-sensor shapes, and the chance distribution for noise
// shapes checked by simulation.
#include <sysid/core/modal_phase_collinearity.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <stdexcept>

#include "random_matrices.hpp"

namespace test_unit_core_modal_phase_collinearity {

using namespace sysid;

using cd = std::complex<double>;

using test::random_complex_vector;

TEST(ModalPhaseCollinearity, RealShapesAreOneWhateverTheirComplexScaling) {
  Eigen::VectorXcd real(4);
  real << 1.0, -2.0, 0.5, 3.0;
  EXPECT_NEAR(sysid::modal_phase_collinearity(real), 1.0, 1e-15);
  EXPECT_NEAR(sysid::modal_phase_collinearity(std::polar(2.0, 0.7) * real), 1.0, 1e-14);
  EXPECT_NEAR(sysid::quadrature_tolerant_collinearity(std::polar(2.0, 0.7) * real), 1.0, 1e-14);
  EXPECT_EQ(sysid::modal_phase_collinearity(Eigen::VectorXcd::Zero(3)), 0.0);
  EXPECT_EQ(sysid::modal_phase_collinearity(Eigen::VectorXcd()), 0.0);
}

TEST(ModalPhaseCollinearity, ByHandForTwoEntries) {
  // phi = (1, e^{i a}): phi^T phi = 1 + e^{2 i a}, |.|^2 = 2 + 2 cos 2a, phi^H phi = 2,
  // MPC = (1 + cos 2a) / 2 = cos^2 a.
  for (const double a : {0.0, 0.3, std::numbers::pi / 4, 1.2, std::numbers::pi / 2}) {
    Eigen::VectorXcd phi(2);
    phi << 1.0, std::polar(1.0, a);
    EXPECT_NEAR(sysid::modal_phase_collinearity(phi), std::cos(a) * std::cos(a), 1e-14) << a;
    // Doubled phases: cos^2 2a; the tolerant value is the larger.
    EXPECT_NEAR(sysid::quadrature_tolerant_collinearity(phi),
                std::max(std::cos(a) * std::cos(a), std::cos(2 * a) * std::cos(2 * a)), 1e-14)
        << a;
  }
}

TEST(ModalPhaseCollinearity, SensorsInQuadratureKeepTheTolerantValue) {
  // A real mode seen by velocity sensors (i w x) on the odd channels and
  // acceleration sensors (-w^2 x) on the even ones.
  Eigen::VectorXcd phi(10);
  for (Eigen::Index j = 0; j < phi.size(); ++j) {
    const double x = std::sin(0.3 * static_cast<double>(j + 1));
    phi(j) = j % 2 == 0 ? cd(-x * 4.0, 0.0) : cd(0.0, 2.0 * x);
  }
  EXPECT_LT(sysid::modal_phase_collinearity(phi), 0.5);
  EXPECT_NEAR(sysid::quadrature_tolerant_collinearity(phi), 1.0, 1e-14);
}

TEST(ModalPhaseCollinearity, EffectiveOutputs) {
  EXPECT_EQ(sysid::shape_effective_outputs(Eigen::VectorXcd::Ones(28)), 28.0);  // 2 x 28 capped at 28
  Eigen::VectorXcd one_hot = Eigen::VectorXcd::Zero(28);
  one_hot(3) = cd(0.0, 5.0);
  EXPECT_EQ(sysid::shape_effective_outputs(one_hot), 2.0);
  EXPECT_EQ(sysid::shape_effective_outputs(Eigen::VectorXcd::Zero(4)), 0.0);
  // Random shapes of 28 equal-variance entries: about 28 on average.
  std::mt19937_64 rng(3);
  double sum = 0.0;
  constexpr int kDraws = 2000;
  for (int k = 0; k < kDraws; ++k) sum += sysid::shape_effective_outputs(random_complex_vector(rng, 28));
  EXPECT_NEAR(sum / kDraws, 28.0, 0.15 * 28.0);
}

TEST(ModalPhaseCollinearity, ChanceDistributionOfANoiseShapeMatchesMauchly) {
  // P(MPC > x) = (1 - x)^((m - 1) / 2) for m independent complex Gaussian entries:
  // the simulated tail at three points within 4 binomial standard errors.
  std::mt19937_64 rng(2026);
  constexpr int kDraws = 40000;
  for (const Eigen::Index m : {5, 28}) {
    const double xs[] = {0.05, 0.2, 0.4};
    int above[3] = {0, 0, 0};
    for (int k = 0; k < kDraws; ++k) {
      const double mpc = sysid::modal_phase_collinearity(random_complex_vector(rng, m));
      for (int j = 0; j < 3; ++j) above[j] += mpc > xs[j];
    }
    for (int j = 0; j < 3; ++j) {
      const double p = std::pow(1.0 - xs[j], 0.5 * static_cast<double>(m - 1));
      const double se = std::sqrt(p * (1.0 - p) / kDraws);
      EXPECT_NEAR(static_cast<double>(above[j]) / kDraws, p, 4.0 * se + 1e-4) << "m = " << m << ", x = " << xs[j];
    }
  }
}

TEST(ModalPhaseCollinearity, TheQuantileHoldsItsLevelForTheTolerantValue) {
  std::mt19937_64 rng(7);
  constexpr int kDraws = 40000;
  constexpr double kLevel = 0.05;
  for (const Eigen::Index m : {20, 28}) {
    const double q = sysid::random_shape_collinearity_quantile(static_cast<double>(m), kLevel);
    int above = 0;
    for (int k = 0; k < kDraws; ++k) above += sysid::quadrature_tolerant_collinearity(random_complex_vector(rng, m)) > q;
    const double rate = static_cast<double>(above) / kDraws;
    // The union bound makes it conservative, and not by much (the two are nearly independent).
    EXPECT_LE(rate, kLevel) << "m = " << m;
    EXPECT_GE(rate, 0.8 * kLevel) << "m = " << m;
  }
  EXPECT_NEAR(sysid::random_shape_collinearity_quantile(28.0, 0.01), 1.0 - std::pow(0.005, 2.0 / 27.0), 1e-15);
}

TEST(ModalPhaseCollinearity, BadQuantileArgumentsAreRefused) {
  EXPECT_THROW(sysid::random_shape_collinearity_quantile(1.0, 0.01), std::invalid_argument);
  EXPECT_THROW(sysid::random_shape_collinearity_quantile(10.0, 0.0), std::invalid_argument);
  EXPECT_THROW(sysid::random_shape_collinearity_quantile(10.0, 1.0), std::invalid_argument);
  EXPECT_THROW(sysid::random_shape_collinearity_quantile(std::nan(""), 0.5), std::invalid_argument);
}

}  // namespace test_unit_core_modal_phase_collinearity
