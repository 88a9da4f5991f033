// Tests for sysid::frequency_response_error (include/sysid/family/estimation_error.hpp):
// on simulated data with white input and known white output noise, the standard
// deviation it reports is Ljung's sqrt(n / N * Phi_v / Phi_u); the band is the one
// the input excites; at() interpolates.
#include <sysid/core/simulate.hpp>
#include <sysid/family/estimation_error.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "random_matrices.hpp"
#include "random_systems.hpp"

namespace test_unit_family_estimation_error {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using sysid::test::kPi;

/// Second-order resonance (f Hz, zeta) in real modal form at sample time Ts.
sysid::StateSpace resonance(double f, double zeta, double Ts) {
  const double w = 2.0 * kPi * f, r = std::exp(-zeta * w * Ts), th = w * std::sqrt(1.0 - zeta * zeta) * Ts;
  MatrixXd A(2, 2), B(2, 1), C(1, 2);
  A << r * std::cos(th), r * std::sin(th), -r * std::sin(th), r * std::cos(th);
  B << 0.0, 1.0;
  C << 1.0, 0.0;
  return sysid::StateSpace(A, B, C, MatrixXd::Zero(1, 1), Ts);
}

/// y = G u + noise, as one experiment.
sysid::IoData simulated_log(const sysid::StateSpace& G, const MatrixXd& u, const MatrixXd& noise) {
  const MatrixXd y = sysid::simulate(G, u) + noise;
  return sysid::IoData(u, y, G.Ts);
}

/// Ratios reported / expected over the bins strictly inside (lo, hi) Hz.
std::vector<double> ratios(const sysid::FrequencyResponseError& e, double expected, double lo, double hi) {
  std::vector<double> r;
  for (Eigen::Index k = 0; k < e.freq_hz.size(); ++k)
    if (e.freq_hz(k) > lo && e.freq_hz(k) < hi) r.push_back(e.standard_deviation(k) / expected);
  return r;
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

}  // namespace

TEST(FamilyEstimationError, SecondOrderWithWhiteInputMatchesLjungsVariance) {
  // n = 2, N = 20000, sigma_u = 1, sigma_v = 0.05: sd = sqrt(2 / 20000 * 0.0025) = 5e-4.
  const double Ts = 1e-3, sigma = 0.05;
  const Eigen::Index N = 20000;
  const sysid::StateSpace G = resonance(60.0, 0.05, Ts);
  const sysid::IoData log = simulated_log(G, sysid::test::white_noise(N, 1, 1), sysid::test::white_noise(N, 1, 2, sigma));
  const sysid::FrequencyResponseError e = sysid::frequency_response_error(G, log);
  ASSERT_EQ(e.freq_hz.size(), e.standard_deviation.size());
  ASSERT_GT(e.freq_hz.size(), 100);
  EXPECT_NEAR(e.freq_hz(e.freq_hz.size() - 1), 500.0, 1e-9) << "Welch bins up to Nyquist";
  const double expected = std::sqrt(2.0 / N * sigma * sigma);
  const std::vector<double> r = ratios(e, expected, 1.0, 499.0);
  ASSERT_GT(r.size(), 100u);
  const double median = quantile(r, 0.5);
  EXPECT_GT(median, 1.0 / 1.15) << "expected " << expected;
  EXPECT_LT(median, 1.15) << "expected " << expected;
  EXPECT_GT(quantile(r, 0.05), 1.0 / 1.5);
  EXPECT_LT(quantile(r, 0.95), 1.5);
  // White input: the whole band up to Nyquist is excited.
  EXPECT_LT(e.band_lo_hz, 2.0);
  EXPECT_GT(e.band_hi_hz, 490.0);
}

TEST(FamilyEstimationError, FirstOrderScalesWithInputPowerAndOrder) {
  // n = 1, N = 16000, sigma_u = 2, sigma_v = 0.1: sd = sqrt(1 / 16000 * 0.01 / 4).
  const double Ts = 0.01, sigma = 0.1;
  const Eigen::Index N = 16000;
  MatrixXd A(1, 1), B(1, 1), C(1, 1), D(1, 1);
  A << 0.9;
  B << 1.0;
  C << 0.1;
  D << 0.5;
  const sysid::StateSpace G(A, B, C, D, Ts);
  const sysid::IoData log = simulated_log(G, sysid::test::white_noise(N, 1, 3, 2.0), sysid::test::white_noise(N, 1, 4, sigma));
  const sysid::FrequencyResponseError e = sysid::frequency_response_error(G, log);
  const double expected = std::sqrt(1.0 / N * sigma * sigma / 4.0);
  const std::vector<double> r = ratios(e, expected, 0.1, 49.9);
  const double median = quantile(r, 0.5);
  EXPECT_GT(median, 1.0 / 1.15) << "expected " << expected;
  EXPECT_LT(median, 1.15) << "expected " << expected;
  EXPECT_LT(quantile(r, 0.95), 1.5);
}

TEST(FamilyEstimationError, SeveralChannelsUseTheLargestNoiseOverTheSmallestInput) {
  // Two inputs (sigma 1 and 3) and two outputs (noise 0.1 and 0.03), n = 4:
  // lambda_max(Phi_v) / lambda_min(Phi_u) -> sd = sqrt(4 / N * 0.1^2 / 1^2).
  const double Ts = 1e-3;
  const Eigen::Index N = 20000;
  const sysid::StateSpace G = sysid::test::rotated_modal_system({40.0, 150.0}, {0.03, 0.05}, 2, 2, 5, Ts);
  MatrixXd u = sysid::test::white_noise(N, 2, 6);
  u.col(1) *= 3.0;
  MatrixXd v = sysid::test::white_noise(N, 2, 7);
  v.col(0) *= 0.1;
  v.col(1) *= 0.03;
  const sysid::FrequencyResponseError e = sysid::frequency_response_error(G, simulated_log(G, u, v));
  const double expected = std::sqrt(4.0 / N * 0.01);
  const std::vector<double> r = ratios(e, expected, 1.0, 499.0);
  const double median = quantile(r, 0.5);
  EXPECT_GT(median, 1.0 / 1.15) << "expected " << expected;
  EXPECT_LT(median, 1.15) << "expected " << expected;
  EXPECT_LT(quantile(r, 0.95), 1.5);
}

TEST(FamilyEstimationError, TheBandIsWhereABandLimitedInputHasPower) {
  // A multisine with lines every 2 Hz from 10 to 100 Hz (random phases).
  const double Ts = 1e-3;
  const Eigen::Index N = 16384;
  MatrixXd u = MatrixXd::Zero(N, 1);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * kPi);
  for (int f = 10; f <= 100; f += 2) {
    const double ph = phase(rng);
    for (Eigen::Index k = 0; k < N; ++k) u(k, 0) += std::sin(2.0 * kPi * f * static_cast<double>(k) * Ts + ph);
  }
  const sysid::StateSpace G = resonance(60.0, 0.05, Ts);
  const sysid::FrequencyResponseError e =
      sysid::frequency_response_error(G, simulated_log(G, u, sysid::test::white_noise(N, 1, 10, 0.01)));
  EXPECT_NEAR(e.band_lo_hz, 10.0, 2.0);
  EXPECT_NEAR(e.band_hi_hz, 100.0, 2.0);
  // Far outside the band the input has no power: the error there is much larger
  // than at a line inside it.
  const Eigen::VectorXd at = e.at((Eigen::VectorXd(2) << 50.0, 300.0).finished());
  EXPECT_GT(at(1), 100.0 * at(0));
}

TEST(FamilyEstimationError, FromAnOutputErrorAtHand) {
  // The overload on the output error itself: white error sigma 0.2, white input
  // sigma 0.5, order 6, N = 12000: sd = sqrt(6 / 12000 * 0.04 / 0.25).
  const Eigen::Index N = 12000;
  const MatrixXd u = sysid::test::white_noise(N, 1, 21, 0.5), v = sysid::test::white_noise(N, 1, 22, 0.2);
  const sysid::FrequencyResponseError e = sysid::frequency_response_error(6, u, v, 0.002);
  EXPECT_NEAR(e.freq_hz(e.freq_hz.size() - 1), 250.0, 1e-9);
  const double expected = std::sqrt(6.0 / N * 0.04 / 0.25);
  const std::vector<double> r = ratios(e, expected, 0.5, 249.5);
  const double median = quantile(r, 0.5);
  EXPECT_GT(median, 1.0 / 1.15) << "expected " << expected;
  EXPECT_LT(median, 1.15) << "expected " << expected;
  // Twice the order: sqrt(2) times the standard deviation, bin by bin.
  const sysid::FrequencyResponseError twice = sysid::frequency_response_error(12, u, v, 0.002);
  for (Eigen::Index k = 0; k < e.freq_hz.size(); ++k)
    EXPECT_NEAR(twice.standard_deviation(k), std::sqrt(2.0) * e.standard_deviation(k), 1e-12 * twice.standard_deviation(k));
  EXPECT_THROW(sysid::frequency_response_error(6, u, v.topRows(N - 1), 0.002), std::invalid_argument);
}

TEST(FamilyEstimationError, AtInterpolatesLinearlyAndHoldsTheEnds) {
  sysid::FrequencyResponseError e;
  e.freq_hz = (VectorXd(3) << 0.0, 10.0, 20.0).finished();
  e.standard_deviation = (VectorXd(3) << 1.0, 3.0, 2.0).finished();
  const VectorXd grid = (VectorXd(8) << -5.0, 0.0, 2.5, 10.0, 15.0, 19.0, 20.0, 30.0).finished();
  const VectorXd got = e.at(grid);
  const VectorXd want = (VectorXd(8) << 1.0, 1.0, 1.5, 3.0, 2.5, 2.1, 2.0, 2.0).finished();
  ASSERT_EQ(got.size(), want.size());
  for (Eigen::Index k = 0; k < want.size(); ++k) EXPECT_NEAR(got(k), want(k), 1e-14) << "at " << grid(k) << " Hz";
  // Empty: no allowance, an empty vector.
  EXPECT_EQ(sysid::FrequencyResponseError{}.at(grid).size(), 0);
}

TEST(FamilyEstimationError, NeedsADiscreteModel) {
  const sysid::StateSpace G = resonance(60.0, 0.05, 1e-3);
  const sysid::IoData log = simulated_log(G, sysid::test::white_noise(2000, 1, 1), sysid::test::white_noise(2000, 1, 2, 0.1));
  sysid::StateSpace continuous = G;
  continuous.Ts = 0.0;
  EXPECT_THROW(sysid::frequency_response_error(continuous, log), std::invalid_argument);
}

}  // namespace test_unit_family_estimation_error
