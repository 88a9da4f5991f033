// Tests for sysid::isolated_spikes and isolated_spike_warnings
// (include/sysid/core/isolated_spikes.hpp).
#include <sysid/core/isolated_spikes.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace test_unit_core_isolated_spikes {

namespace {

using Eigen::VectorXd;

VectorXd white(Eigen::Index n, std::uint64_t seed, double sigma = 1.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  VectorXd x(n);
  for (auto& v : x) v = g(rng);
  return x;
}

/// A lightly damped 40 Hz oscillation at 1 kHz: smooth at the sampling rate.
VectorXd ringing(Eigen::Index n) {
  VectorXd x(n);
  for (Eigen::Index t = 0; t < n; ++t)
    x(t) = std::exp(-0.001 * static_cast<double>(t)) * std::sin(2.0 * std::numbers::pi * 0.04 * static_cast<double>(t));
  return x;
}

TEST(IsolatedSpikes, FindsGlitchesAndOnlyThem) {
  VectorXd y = ringing(5000) + white(5000, 1, 0.01);
  EXPECT_TRUE(sysid::isolated_spikes(y).empty());
  y(1234) += 5.0;
  y(4000) -= 8.0;
  const auto spikes = sysid::isolated_spikes(y);
  ASSERT_EQ(spikes.size(), 2u);
  EXPECT_EQ(spikes[0], 1234);
  EXPECT_EQ(spikes[1], 4000);
}

TEST(IsolatedSpikes, RingingNearNyquistAfterATapIsNotASpike) {
  // A 330 Hz mode (damping 2 %) at 1024 Hz, struck every 5 s in low noise: about
  // three samples per period, so the peaks depart from both neighbours by far
  // more than the quiet part's scale, yet every step around them is large too.
  const Eigen::Index n = 20480;
  VectorXd y = white(n, 5, 1e-4);
  const double w = 2.0 * std::numbers::pi * 330.0 / 1024.0, decay = 0.02 * w;
  for (Eigen::Index tap : {1000, 6120, 11240, 16360})
    for (Eigen::Index k = 0; k < 400; ++k)
      y(tap + k) += std::exp(-decay * static_cast<double>(k)) * std::sin(w * static_cast<double>(k));
  EXPECT_TRUE(sysid::isolated_spikes(y).empty());
  y(9000) += 0.5;  // a glitch in the quiet part is still found
  ASSERT_EQ(sysid::isolated_spikes(y).size(), 1u);
  EXPECT_EQ(sysid::isolated_spikes(y).front(), 9000);
}

TEST(IsolatedSpikes, WhiteNoiseAndStepsAreNotSpikes) {
  // 10^5 Gaussian samples: no false alarm at 12 sigma of the difference.
  EXPECT_TRUE(sysid::isolated_spikes(white(100000, 2)).empty());
  // A step departs from one neighbour only.
  VectorXd step = white(2000, 3, 0.01);
  step.tail(1000).array() += 5.0;
  EXPECT_TRUE(sysid::isolated_spikes(step).empty());
}

TEST(IsolatedSpikes, QuantisedSignalsUseTheRmsWhenTheMadIsZero) {
  // Mostly constant (MAD of the difference zero): the RMS scale still finds a glitch
  // far above the occasional one-count change.
  VectorXd y = VectorXd::Zero(3000);
  for (Eigen::Index t = 500; t < 3000; t += 500) y.tail(3000 - t).array() += 1.0;
  EXPECT_TRUE(sysid::isolated_spikes(y).empty());
  y(1700) += 100.0;
  const auto spikes = sysid::isolated_spikes(y);
  ASSERT_EQ(spikes.size(), 1u);
  EXPECT_EQ(spikes[0], 1700);
}

sysid::IoData one_experiment(const VectorXd& u, const VectorXd& y) {
  sysid::IoData d;
  d.Ts = 1e-3;
  d.input_names = {"force"};
  d.output_names = {"accel"};
  sysid::Experiment e;
  e.u = u;
  e.y = y;
  d.experiments.push_back(std::move(e));
  return d;
}

TEST(IsolatedSpikes, WarningCountsAcrossExperimentsAndSparesInputImpulses) {
  // A hammer tap: the force is an impulse and the accelerometer (direct
  // feedthrough) jumps with it — not a glitch. A glitch elsewhere is reported.
  VectorXd u = white(4000, 4, 1e-3);
  u(1000) = 10.0;
  VectorXd y = ringing(4000) + white(4000, 5, 1e-3);
  y(1000) += 3.0;  // feedthrough of the tap
  EXPECT_TRUE(sysid::isolated_spike_warnings(one_experiment(u, y), "x").empty());
  y(2500) += 3.0;  // a glitch
  const auto warnings = sysid::isolated_spike_warnings(one_experiment(u, y), "arx");
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind("arx: output accel has 1 isolated spike (sample 2500", 0), 0u) << warnings[0];
}

}  // namespace

}  // namespace test_unit_core_isolated_spikes
