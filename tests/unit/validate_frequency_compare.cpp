// Unit tests of validate/frequency_compare.hpp: the in-band, coherence-weighted
// relative error of a model's FRF against the non-parametric H1 of the data.
#include <sysid/core/simulate.hpp>
#include <sysid/validate/frequency_compare.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "random_matrices.hpp"

namespace test_unit_validate_frequency_compare {

using namespace sysid;

namespace {

/// Real modal block of a mode (freq_hz, zeta) at sample time Ts: z = exp(s Ts).
Eigen::Matrix2d mode_block(double f, double zeta, double Ts) {
  const double w = 2.0 * std::numbers::pi * f;
  const double r = std::exp(-zeta * w * Ts), th = w * std::sqrt(1.0 - zeta * zeta) * Ts;
  Eigen::Matrix2d a;
  a << r * std::cos(th), r * std::sin(th), -r * std::sin(th), r * std::cos(th);
  return a;
}

/// SISO plant with modes at f1 (zeta 0.02) and 120 Hz (zeta 0.05), fs = 1 kHz.
StateSpace plant(double f1 = 50.0) {
  const double Ts = 0.001;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4);
  A.block(0, 0, 2, 2) = mode_block(f1, 0.02, Ts);
  A.block(2, 2, 2, 2) = mode_block(120.0, 0.05, Ts);
  Eigen::MatrixXd B(4, 1), C(1, 4);
  B << 0, 1, 0, 3;
  C << 1, 0, 1, 0;
  return StateSpace(A, B, C, Eigen::MatrixXd::Zero(1, 1), Ts);
}

/// 2-input 2-output plant: the same two modes, every input reaching every output.
StateSpace mimo_plant() {
  const double Ts = 0.001;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4);
  A.block(0, 0, 2, 2) = mode_block(50.0, 0.02, Ts);
  A.block(2, 2, 2, 2) = mode_block(120.0, 0.05, Ts);
  Eigen::MatrixXd B(4, 2), C(2, 4);
  B << 0, 0.5, 1, 0.2, 0.3, 0, 2, 3;
  C << 1, 0, 1, 0, 0.5, 0.2, -1, 0;
  return StateSpace(A, B, C, Eigen::MatrixXd::Zero(2, 2), Ts);
}

/// White-noise input, output with white measurement noise of the given level.
IoData record(const StateSpace& sys, Eigen::Index n, double noise, std::uint64_t seed) {
  const Eigen::MatrixXd u = sysid::test::white_noise(n, sys.inputs(), seed, 1.0);
  const Eigen::MatrixXd y = simulate(sys, u) + sysid::test::white_noise(n, sys.outputs(), seed + 1, noise);
  return IoData(u, y, sys.Ts);
}

FrequencyCompareOptions band(double lo, double hi) {
  FrequencyCompareOptions o;
  o.frf.welch.nfft = 4096;
  o.f_lo_hz = lo;
  o.f_hi_hz = hi;
  return o;
}

}  // namespace

TEST(ValidateFrequencyCompare, TrueModelIsWithinTheNoiseFloor) {
  const StateSpace sys = plant();
  const IoData data = record(sys, 200000, 0.1, 1);
  const FrequencyCompareResult r = frequency_compare(sys, data, band(0.0, 200.0));
  ASSERT_EQ(r.pairs.size(), 1u);
  const FrequencyComparePair& p = r.pairs[0];
  // 96 Hann segments of 4096 (n_d ~ 50) and coherence ~ 0.99 give a random error of H
  // of a few per cent (noise_floor); the resolution bias of the lightly damped 50 Hz
  // mode, -(1/3)(B_e/B_r)^2 with B_e = 1.5 x 0.244 Hz (Hann) and B_r = 2 zeta f = 2 Hz
  // (Bendat & Piersol eq. 8.141), is ~1 % at the peak. 0.08 bounds both.
  EXPECT_LT(p.relative_error, 0.08) << "noise floor " << p.noise_floor;
  EXPECT_GT(p.noise_floor, 0.0);
  EXPECT_LT(p.noise_floor, 0.05);
  EXPECT_GT(p.mean_coherence, 0.9);
  EXPECT_EQ(r.bins_in_band, 820);  // bins 0..819 at 1000/4096 Hz: 819 * 0.244 = 199.95 Hz
  EXPECT_DOUBLE_EQ(r.f_hi_hz, 200.0);
}

TEST(ValidateFrequencyCompare, WrongResonanceIsLargeAndLocated) {
  const IoData data = record(plant(50.0), 60000, 0.1, 2);
  const FrequencyCompareResult r = frequency_compare(plant(60.0), data, band(0.0, 200.0));
  const FrequencyComparePair& p = r.pairs[0];
  // The model's resonance is 10 half-power bandwidths away from the real one: around
  // 50 Hz |G - H| ~ |H| (the peak is missing), so the error is of order 1.
  EXPECT_GT(p.relative_error, 0.5);
  EXPECT_GT(p.worst_freq_hz, 45.0);
  EXPECT_LT(p.worst_freq_hz, 65.0);
  EXPECT_GT(p.worst_mismatch, 1.0);
}

TEST(ValidateFrequencyCompare, GainErrorReadsAsItsRatioPerPair) {
  const StateSpace sys = mimo_plant();
  const IoData data = record(sys, 200000, 0.05, 3);
  StateSpace wrong = sys;
  wrong.C.row(1) *= 1.3;  // output 2 reads 30 % high
  const FrequencyCompareResult r = frequency_compare(wrong, data, band(5.0, 300.0));
  ASSERT_EQ(r.pairs.size(), 4u);
  // G = 1.3 H_true on output 2: |G - H| / |H| = 0.3 at every bin up to the estimate's
  // own error (a few per cent, see the SISO test), so the weighted error is 0.3 +- 0.05.
  for (const auto& p : r.pairs) {
    if (p.output == 1)
      EXPECT_NEAR(p.relative_error, 0.3, 0.05) << p.output << "," << p.input;
    else
      EXPECT_LT(p.relative_error, 0.08) << p.output << "," << p.input;
  }
  EXPECT_EQ(r.pairs[2].output, 1);
  EXPECT_EQ(r.pairs[2].input, 0);
}

TEST(ValidateFrequencyCompare, BandLimitsAndPreconditions) {
  const StateSpace sys = plant();
  const IoData data = record(sys, 8000, 0.1, 4);
  // The band is clipped to Nyquist.
  const FrequencyCompareResult r = frequency_compare(sys, data, band(100.0, 1e9));
  EXPECT_DOUBLE_EQ(r.f_hi_hz, 500.0);
  for (const auto& m : r.model_frf) EXPECT_EQ(m.rows(), 1);
  EXPECT_THROW(frequency_compare(sys, data, band(50.0, 50.0)), std::invalid_argument);
  EXPECT_THROW(frequency_compare(sys, data, band(600.0, 700.0)), std::invalid_argument);  // no bin
  StateSpace other_rate = sys;
  other_rate.Ts = 0.002;
  EXPECT_THROW(frequency_compare(other_rate, data, band(0.0, 100.0)), std::invalid_argument);
  EXPECT_THROW(frequency_compare(mimo_plant(), data, band(0.0, 100.0)), std::invalid_argument);
}

}  // namespace test_unit_validate_frequency_compare
