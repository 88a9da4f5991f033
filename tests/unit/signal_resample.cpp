// Unit tests of signal/resample.hpp: decimation behind a Butterworth anti-alias
// filter and rational resampling with a polyphase windowed-sinc filter.
#include <sysid/signal/resample.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include "random_matrices.hpp"

namespace test_unit_signal_resample {

using namespace sysid;

namespace {

using sysid::test::kPi;
/// sin(2 pi f t + phi) at t = k / fs, k = 0..n-1 (f and fs in the same unit).
Eigen::VectorXd tone(Eigen::Index n, double f, double fs, double phi = 0.3) {
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) x(k) = std::sin(2.0 * kPi * f * static_cast<double>(k) / fs + phi);
  return x;
}

double rms(const Eigen::VectorXd& x) { return std::sqrt(x.squaredNorm() / static_cast<double>(x.size())); }

}  // namespace

TEST(SignalDecimate, PassbandToneKeptWithZeroPhaseAndDesignedGain) {
  const int r = 5;
  const Eigen::Index n = 20000;
  const double f = 0.01;  // cycles per sample; new Nyquist 0.1, cutoff 0.08
  const Eigen::VectorXd x = tone(n, f, 1.0);
  const Eigen::MatrixXd y = decimate(x, r);
  ASSERT_EQ(y.rows(), n / r);
  // Zero phase: y[k] = |H(f)|^2 x[k r] exactly in steady state; the Gustafsson edges
  // leave transients of a few filter time constants only (1000 samples of margin).
  const SecondOrderSections lp = butterworth(8, BandType::lowpass, 0.8 * 1.0 / (2.0 * r), 0.0, 1.0);
  const double g2 = std::norm(sos_frequency_response(lp, f));
  EXPECT_GT(g2, 0.99);  // deep in the passband of an 8th-order Butterworth: |H|^2 = 1/(1 + (1/8)^16)
  for (Eigen::Index k = 200; k < y.rows() - 200; ++k) ASSERT_NEAR(y(k, 0), g2 * x(k * r), 1e-6) << k;
}

TEST(SignalDecimate, AliasBandIsAttenuatedAsDesigned) {
  const int r = 4;
  const Eigen::Index n = 40000;
  const double f = 0.2;  // above the new Nyquist 0.125: would alias to 0.05 without the filter
  const Eigen::MatrixXd y = decimate(tone(n, f, 1.0), r);
  const SecondOrderSections lp = butterworth(8, BandType::lowpass, 0.1, 0.0, 1.0);
  const double g2 = std::norm(sos_frequency_response(lp, f));
  // Forward-backward: the residual is a sine of amplitude |H(f)|^2 (RMS /sqrt 2).
  const double expected = g2 / std::sqrt(2.0);
  const Eigen::VectorXd mid = y.col(0).segment(500, y.rows() - 1000);
  EXPECT_NEAR(rms(mid), expected, 0.02 * expected);
  EXPECT_LT(rms(mid), 1e-3);  // |H(0.2)|^2 = 1/(1 + 2^16) ~ 1.5e-5 up to prewarping
}

TEST(SignalDecimate, IoDataOverloadIsTheN4sidRecipe) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  Eigen::MatrixXd u(3001, 2), y(3001, 1);
  for (Eigen::Index i = 0; i < u.size(); ++i) u.data()[i] = g(rng);
  for (Eigen::Index i = 0; i < y.size(); ++i) y.data()[i] = g(rng);
  const double Ts = 0.0005;
  IoData data(u, y, Ts, {"a", "b"}, {"c"}, "log.csv");
  const int r = 3;
  const IoData d = decimate(data, r);
  EXPECT_DOUBLE_EQ(d.Ts, r * Ts);
  EXPECT_EQ(d.input_names, data.input_names);
  EXPECT_EQ(d.output_names, data.output_names);
  ASSERT_EQ(d.experiments.size(), 1u);
  EXPECT_EQ(d.experiments[0].source, "log.csv");
  // The recipe of src/n4sid.cpp detail::decimate, written out: 8th-order zero-phase
  // Butterworth at 0.8 x the new Nyquist, then every r-th sample, ceil(N / r) rows.
  const double fs = 1.0 / Ts;
  const SecondOrderSections lp = butterworth(8, BandType::lowpass, 0.8 * fs / (2.0 * r), 0.0, fs);
  const Eigen::MatrixXd uf = filtfilt(lp, u), yf = filtfilt(lp, y);
  ASSERT_EQ(d.experiments[0].u.rows(), 1001);
  for (Eigen::Index k = 0; k < 1001; ++k) {
    ASSERT_EQ(d.experiments[0].u.row(k), uf.row(k * r)) << k;
    ASSERT_EQ(d.experiments[0].y.row(k), yf.row(k * r)) << k;
  }
}

TEST(SignalDecimate, CausalOptionAndOffset) {
  const Eigen::VectorXd x = tone(1000, 0.02, 1.0);
  DecimateOptions o;
  o.zero_phase = false;
  o.offset = 2;
  o.order = 4;
  const Eigen::MatrixXd y = decimate(x, 3, o);
  const Eigen::MatrixXd f = sos_filter(butterworth(4, BandType::lowpass, 0.8 / 6.0, 0.0, 1.0), x);
  ASSERT_EQ(y.rows(), (1000 - 2 + 2) / 3);
  for (Eigen::Index k = 0; k < y.rows(); ++k) ASSERT_EQ(y(k, 0), f(2 + 3 * k, 0));
  EXPECT_EQ(decimate(x, 1), Eigen::MatrixXd(x));  // r = 1: unchanged
}

TEST(SignalDecimate, Preconditions) {
  const Eigen::VectorXd x = tone(100, 0.01, 1.0);
  EXPECT_THROW(decimate(x, 0), std::invalid_argument);
  EXPECT_THROW(decimate(x, 2, {.cutoff_fraction = 1.0}), std::invalid_argument);
  EXPECT_THROW(decimate(x, 2, {.order = 0}), std::invalid_argument);
  EXPECT_THROW(decimate(x, 2, {.offset = 2}), std::invalid_argument);
  EXPECT_THROW(decimate(Eigen::VectorXd::Ones(10), 2), std::invalid_argument);  // shorter than filtfilt's padding
}

TEST(SignalResample, UpByThreeHalvesReproducesAnInBandTone) {
  const Eigen::Index n = 3000;
  const double fs = 2000.0, f = 100.0;
  const Eigen::VectorXd x = tone(n, f, fs);
  const Eigen::MatrixXd y = resample_poly(x, 3, 2);
  ASSERT_EQ(y.rows(), 4500);  // ceil(3000 * 3 / 2)
  // y[m] is the signal at t = m / 3000 s. Passband ripple of a Kaiser(beta 5) design
  // is ~3e-3 (Kaiser 1974: delta ~ 10^(-A/20), A ~ 50 dB); 1e-2 gives margin.
  const Eigen::VectorXd want = tone(4500, f, 3000.0);
  for (Eigen::Index m = 0; m < y.rows(); ++m) ASSERT_NEAR(y(m, 0), want(m), 1e-2) << m;
}

TEST(SignalResample, DownByTwoThirdsRejectsWhatWouldAlias) {
  const Eigen::Index n = 6000;
  // New rate 2/3 fs, Nyquist fs/3. An in-band tone at 0.05 fs is kept ...
  const Eigen::MatrixXd keep = resample_poly(tone(n, 0.05, 1.0), 2, 3);
  ASSERT_EQ(keep.rows(), 4000);
  const Eigen::VectorXd want = tone(4000, 0.05, 2.0 / 3.0);
  EXPECT_LT((keep.col(0) - want).cwiseAbs().maxCoeff(), 1e-2);
  // ... one at 0.45 fs (above fs/3 by more than the ~0.05 fs half transition band) is
  // removed to the stopband level ~ -50 dB: RMS < 0.01 of the input's 0.707.
  const Eigen::MatrixXd gone = resample_poly(tone(n, 0.45, 1.0), 2, 3);
  EXPECT_LT(rms(gone.col(0).segment(100, 3800)), 0.01 * std::sqrt(0.5));
}

TEST(SignalResample, ConstantsExactIdentityAndGcd) {
  const Eigen::MatrixXd c = Eigen::MatrixXd::Constant(50, 2, 3.5);
  const Eigen::MatrixXd y = resample_poly(c, 5, 3);
  ASSERT_EQ(y.rows(), 84);  // ceil(250 / 3)
  // Each polyphase branch sums to 1: a constant passes to rounding.
  EXPECT_LT((y.array() - 3.5).abs().maxCoeff(), 1e-12);
  const Eigen::VectorXd x = tone(300, 0.1, 1.0);
  EXPECT_EQ(resample_poly(x, 4, 4), Eigen::MatrixXd(x));
  EXPECT_EQ(resample_poly(x, 6, 4), resample_poly(x, 3, 2));
}

TEST(SignalResample, MultiColumnIsColumnByColumn) {
  Eigen::MatrixXd x(800, 2);
  x.col(0) = tone(800, 0.03, 1.0);
  x.col(1) = tone(800, 0.07, 1.0, 1.1);
  const Eigen::MatrixXd y = resample_poly(x, 2, 5);
  EXPECT_EQ(y.col(0), resample_poly(Eigen::VectorXd(x.col(0)), 2, 5).col(0));
  EXPECT_EQ(y.col(1), resample_poly(Eigen::VectorXd(x.col(1)), 2, 5).col(0));
}

TEST(SignalResample, Preconditions) {
  const Eigen::VectorXd x = tone(100, 0.01, 1.0);
  EXPECT_THROW(resample_poly(x, 0, 1), std::invalid_argument);
  EXPECT_THROW(resample_poly(x, 1, 0), std::invalid_argument);
  EXPECT_THROW(resample_poly(Eigen::VectorXd::Ones(1), 2, 1), std::invalid_argument);
  Eigen::VectorXd bad = x;
  bad(3) = std::nan("");
  EXPECT_THROW(resample_poly(bad, 2, 1), std::invalid_argument);
  EXPECT_THROW(resample_poly(x, 2, 1, {.cutoff_fraction = 0.0}), std::invalid_argument);
}

}  // namespace test_unit_signal_resample
