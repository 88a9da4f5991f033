// Tests of spectral/welch.hpp, spectral/periodogram.hpp, spectral/window.hpp and
// spectral/confidence.hpp: levels, Parseval, cross-spectra conventions, degrees of
// freedom and preconditions.
#include <sysid/spectral/confidence.hpp>
#include <sysid/spectral/periodogram.hpp>
#include <sysid/spectral/welch.hpp>
#include <sysid/spectral/window.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include "random_systems.hpp"

namespace test_unit_spectral_welch {

namespace {

using sysid::Detrend;
using sysid::SpectralScaling;
using sysid::WelchOptions;
using sysid::WindowType;
using sysid::test::white_noise;

const WindowType kWindows[] = {WindowType::rectangular, WindowType::hann, WindowType::hamming, WindowType::blackman_harris,
                               WindowType::flattop};

TEST(SpectralWindow, ShapesAndNames) {
  for (WindowType w : kWindows) {
    const Eigen::VectorXd v = sysid::make_window(w, 64);
    // Periodic windows are symmetric about n = L/2: w[n] = w[L - n].
    for (Eigen::Index n = 1; n < 64; ++n) EXPECT_NEAR(v(n), v(64 - n), 1e-14);
    EXPECT_NEAR(v.maxCoeff(), w == WindowType::flattop ? 1.000000003 : 1.0, 1e-6) << sysid::window_name(w);
    EXPECT_EQ(sysid::parse_window(sysid::window_name(w)), w);
  }
  EXPECT_NEAR(sysid::make_window(WindowType::hann, 8)(0), 0.0, 1e-15);
  EXPECT_NEAR(sysid::make_window(WindowType::hamming, 8)(0), 0.08, 1e-15);
}

// White noise of variance s^2 has the one-sided density s^2 / (fs/2). Each interior
// bin of the Welch estimate is s^2 (2/fs) chi2(nu)/nu; with a 99 % interval at most
// ~1 % of the bins miss, so >= 95 % must cover (the chi-square approximation and the
// Wilson-Hilferty quantiles are good to ~1 % at nu ~ 480).
TEST(SpectralWelch, WhiteNoiseLevelWithinChiSquareBound) {
  const double fs = 1000.0, sigma = 2.0;
  const Eigen::MatrixXd x = white_noise(1 << 18, 2, 11, sigma);
  WelchOptions o;
  o.nfft = 1024;
  const sysid::PowerSpectrum ps = sysid::welch_psd(x, fs, o);
  ASSERT_EQ(ps.freq_hz.size(), 513);
  EXPECT_EQ(ps.segments, 1 + ((1 << 18) - 1024) / 512);
  // Hann, 50 % overlap: rho_1 = 1/6, so nu = 2K / (1 + 2 (1 - 1/K) / 36) ~ 1.895 K.
  EXPECT_NEAR(ps.dof / static_cast<double>(ps.segments), 2.0 / (1.0 + 2.0 / 36.0), 0.01);
  const double truth = sigma * sigma * 2.0 / fs;
  const auto [lo, hi] = sysid::psd_confidence_factors(ps.dof, 0.99);
  for (Eigen::Index c = 0; c < 2; ++c) {
    int covered = 0, total = 0;
    double mean = 0.0, meansq = 0.0;
    for (Eigen::Index k = 1; k + 1 < ps.freq_hz.size(); ++k) {
      const double s = ps.psd(k, c);
      covered += (lo * s <= truth && truth <= hi * s) ? 1 : 0;
      ++total;
      mean += s / truth;
      meansq += (s / truth) * (s / truth);
    }
    mean /= total;
    meansq /= total;
    EXPECT_GE(covered, 0.95 * total) << "channel " << c;
    // The mean over 511 bins has relative s.d. ~ sqrt(2/nu/511) ~ 0.3 %.
    EXPECT_NEAR(mean, 1.0, 0.015);
    // Empirical degrees of freedom 2 mean^2 / var agree with Welch's formula (adjacent
    // Hann bins are correlated, so the variance estimate itself is good to ~15 %).
    const double nu_emp = 2.0 / (meansq - mean * mean);
    EXPECT_NEAR(nu_emp / ps.dof, 1.0, 0.2);
  }
}

// Parseval: with density scaling, sum_k S(f_k) fs/nfft equals the mean over segments
// of sum_n (w_n x_n)^2 / sum_n w_n^2 exactly (any window), and the variance in expectation.
TEST(SpectralWelch, ParsevalForEveryWindow) {
  const double fs = 250.0;
  const Eigen::MatrixXd x = white_noise(20000, 1, 5, 1.5);
  for (WindowType w : kWindows) {
    WelchOptions o;
    o.nfft = 500;  // not a power of two: exercises the generic kissfft path
    o.overlap = 0.3;
    o.window = w;
    o.detrend = Detrend::none;
    const sysid::PowerSpectrum ps = sysid::welch_psd(x, fs, o);
    const Eigen::VectorXd win = sysid::make_window(w, 500);
    const Eigen::Index step = 350;
    double direct = 0.0;
    for (Eigen::Index s = 0; s < ps.segments; ++s)
      direct += (x.col(0).segment(s * step, 500).cwiseProduct(win)).squaredNorm() / win.squaredNorm();
    direct /= static_cast<double>(ps.segments);
    const double integral = ps.psd.col(0).sum() * fs / 500.0;
    EXPECT_NEAR(integral / direct, 1.0, 1e-12) << sysid::window_name(w);
    // Variance 2.25; the windowed mean square over ~57 segments of 500 samples has
    // relative s.d. below ~sqrt(2 / (57 * 500 * 0.3)) ~ 1.5 %: 6 % is 4 s.d.
    EXPECT_NEAR(integral / 2.25, 1.0, 0.06) << sysid::window_name(w);
  }
}

TEST(SpectralPeriodogram, ParsevalExactAndZeroPadding) {
  const double fs = 10.0;
  for (Eigen::Index n : {Eigen::Index(1000), Eigen::Index(999)}) {  // even and odd lengths
    const Eigen::MatrixXd x = white_noise(n, 2, 3, 1.0);
    sysid::PeriodogramOptions o;
    o.detrend = Detrend::none;
    for (Eigen::Index nfft : {Eigen::Index(0), Eigen::Index(1500)}) {
      o.nfft = nfft;
      const sysid::PowerSpectrum ps = sysid::periodogram(x, fs, o);
      const Eigen::Index L = nfft == 0 ? n : nfft;
      ASSERT_EQ(ps.freq_hz.size(), L / 2 + 1);
      EXPECT_NEAR(ps.freq_hz(1), fs / static_cast<double>(L), 1e-12);
      EXPECT_EQ(ps.segments, 1);
      EXPECT_NEAR(ps.dof, 2.0, 1e-12);
      for (Eigen::Index c = 0; c < 2; ++c)
        EXPECT_NEAR(ps.psd.col(c).sum() * fs / static_cast<double>(L), x.col(c).squaredNorm() / static_cast<double>(n), 1e-10);
    }
  }
}

TEST(SpectralWelch, CsdWithItselfIsPsdAndHermitian) {
  const double fs = 100.0;
  Eigen::MatrixXd x = white_noise(8192, 3, 21, 1.0);
  x.col(1) += 0.5 * x.col(0);  // correlated channels: non-trivial off-diagonal terms
  WelchOptions o;
  o.nfft = 256;
  o.window = WindowType::hamming;
  o.detrend = Detrend::linear;
  const sysid::CrossSpectrum cs = sysid::welch_csd(x, x, fs, o);
  const sysid::PowerSpectrum ps = sysid::welch_psd(x, fs, o);
  ASSERT_EQ(cs.csd.size(), static_cast<std::size_t>(ps.freq_hz.size()));
  EXPECT_EQ(cs.segments, ps.segments);
  EXPECT_DOUBLE_EQ(cs.dof, ps.dof);
  for (std::size_t k = 0; k < cs.csd.size(); ++k) {
    const Eigen::MatrixXcd& S = cs.csd[k];
    for (Eigen::Index i = 0; i < 3; ++i) {
      EXPECT_NEAR(S(i, i).real(), ps.psd(static_cast<Eigen::Index>(k), i), 1e-12 * ps.psd.maxCoeff());
      EXPECT_EQ(S(i, i).imag(), 0.0);
    }
    EXPECT_LT((S - S.adjoint()).norm(), 1e-12 * S.norm());
  }
}

// Convention check: y[n] = g x[n - d] has S_xy = g exp(-i 2 pi f d / fs) S_xx (conjugate on x).
TEST(SpectralWelch, CsdConventionDelayedCopy) {
  const double fs = 1000.0, g = 0.7;
  const Eigen::Index d = 3, n = 1 << 16;
  const Eigen::MatrixXd x = white_noise(n + d, 1, 8, 1.0);
  const Eigen::MatrixXd a = x.bottomRows(n), b = g * x.topRows(n);  // b[k] = g x[k + d - d] lags a by d
  WelchOptions o;
  o.nfft = 1024;
  const sysid::CrossSpectrum cs = sysid::welch_csd(a, b, fs, o);
  const sysid::PowerSpectrum pa = sysid::welch_psd(a, fs, o);
  for (Eigen::Index k = 20; k < 500; k += 37) {
    const std::complex<double> ratio = cs.csd[static_cast<std::size_t>(k)](0, 0) / pa.psd(k, 0);
    const std::complex<double> expect = g * std::exp(std::complex<double>(0.0, -2.0 * std::numbers::pi * cs.freq_hz(k) * d / fs));
    // The delay shifts 3 of 1024 samples out of each segment: a bias ~0.3 %, plus
    // random error ~ 1/sqrt(nd) ~ 0 (noise-free); 2 % leaves room for the window's leakage.
    EXPECT_LT(std::abs(ratio - expect), 0.02) << "f = " << cs.freq_hz(k);
  }
}

TEST(SpectralWelch, LinearDetrendRemovesRampExactly) {
  const double fs = 50.0;
  const Eigen::MatrixXd w = white_noise(5000, 1, 4, 1.0);
  Eigen::MatrixXd ramp = w;
  for (Eigen::Index k = 0; k < 5000; ++k) ramp(k, 0) += 3.0 + 0.01 * static_cast<double>(k);
  WelchOptions o;
  o.nfft = 512;
  o.detrend = Detrend::linear;
  const sysid::PowerSpectrum a = sysid::welch_psd(w, fs, o), b = sysid::welch_psd(ramp, fs, o);
  EXPECT_LT((a.psd - b.psd).norm(), 1e-9 * a.psd.norm());
  o.detrend = Detrend::mean;  // a mean-only detrend leaves the ramp's energy at low frequencies
  const sysid::PowerSpectrum c = sysid::welch_psd(ramp, fs, o);
  EXPECT_GT(c.psd(1, 0), 10.0 * a.psd(1, 0));
}

// A sine of amplitude A at a frequency between bins reads A^2/2 with the flattop
// window and spectrum scaling (its scalloping loss is < 0.01 dB = 0.23 % in power).
TEST(SpectralWelch, FlattopSpectrumScalingReadsSinePower) {
  const double fs = 1000.0, f0 = 123.4, A = 3.0;
  Eigen::MatrixXd x(16384, 1);
  for (Eigen::Index k = 0; k < x.rows(); ++k) x(k, 0) = A * std::sin(2.0 * std::numbers::pi * f0 * static_cast<double>(k) / fs + 0.3);
  WelchOptions o;
  o.nfft = 1024;
  o.window = WindowType::flattop;
  o.scaling = SpectralScaling::spectrum;
  const sysid::PowerSpectrum ps = sysid::welch_psd(x, fs, o);
  EXPECT_NEAR(ps.psd.col(0).maxCoeff() / (A * A / 2.0), 1.0, 0.003);
}

TEST(SpectralWelch, NfftHalvedForShortRecords) {
  const Eigen::MatrixXd x = white_noise(700, 1, 1, 1.0);
  const sysid::PowerSpectrum ps = sysid::welch_psd(x, 1.0, WelchOptions{});
  EXPECT_EQ(ps.nfft, 512);
  EXPECT_EQ(ps.freq_hz.size(), 257);
  EXPECT_NEAR(ps.freq_hz(256), 0.5, 1e-15);
  EXPECT_EQ(ps.segments, 1);
}

TEST(SpectralWelch, BadArgumentsThrow) {
  const Eigen::MatrixXd x = white_noise(100, 1, 1, 1.0);
  WelchOptions o;
  o.nfft = 32;
  EXPECT_THROW(sysid::welch_psd(x, 0.0, o), std::invalid_argument);
  EXPECT_THROW(sysid::welch_psd(x, std::nan(""), o), std::invalid_argument);
  WelchOptions bad = o;
  bad.nfft = 4;
  EXPECT_THROW(sysid::welch_psd(x, 1.0, bad), std::invalid_argument);
  bad = o;
  bad.overlap = 1.0;
  EXPECT_THROW(sysid::welch_psd(x, 1.0, bad), std::invalid_argument);
  bad.overlap = -0.1;
  EXPECT_THROW(sysid::welch_psd(x, 1.0, bad), std::invalid_argument);
  EXPECT_THROW(sysid::welch_psd(Eigen::MatrixXd(x.topRows(5)), 1.0, o), std::invalid_argument);
  Eigen::MatrixXd nan = x;
  nan(10, 0) = std::nan("");
  EXPECT_THROW(sysid::welch_psd(nan, 1.0, o), std::invalid_argument);
  EXPECT_THROW(sysid::welch_csd(x, Eigen::MatrixXd(x.topRows(99)), 1.0, o), std::invalid_argument);
  EXPECT_THROW(sysid::welch_csd(x, Eigen::MatrixXd(100, 0), 1.0, o), std::invalid_argument);
  sysid::PeriodogramOptions po;
  po.nfft = 50;
  EXPECT_THROW(sysid::periodogram(x, 1.0, po), std::invalid_argument);
  EXPECT_THROW(sysid::parse_window("kaiser"), std::invalid_argument);
  EXPECT_THROW(sysid::make_window(WindowType::hann, 0), std::invalid_argument);
  EXPECT_THROW(sysid::psd_confidence_factors(10.0, 1.0), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_spectral_welch
