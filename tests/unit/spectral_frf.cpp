// Tests of spectral/frf.hpp (H1, H2, coherences, confidence bounds, MIMO) and
// spectral/etfe.hpp, against known discrete-time systems.
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/signal/excitation.hpp>
#include <sysid/spectral/etfe.hpp>
#include <sysid/spectral/frf.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>
#include "random_systems.hpp"

namespace test_unit_spectral_frf {

namespace {

constexpr double kFs = 1000.0;

using sysid::test::white_noise;

/// Second-order resonance block (poles r e^{+-i theta}) in controllable form.
void resonance(Eigen::MatrixXd& A, Eigen::Index at, double f0, double zeta) {
  const double w0 = 2.0 * std::numbers::pi * f0, Ts = 1.0 / kFs;
  const double r = std::exp(-zeta * w0 * Ts), th = w0 * Ts * std::sqrt(1.0 - zeta * zeta);
  A(at, at) = 2.0 * r * std::cos(th);
  A(at, at + 1) = -r * r;
  A(at + 1, at) = 1.0;
}

/// SISO: a resonance at 100 Hz (zeta 0.1) plus a feedthrough 0.5, which puts an
/// antiresonance at 134 Hz (|G| down to 0.024; elsewhere 0.2 .. 2): the coherence
/// with output noise spans almost 0 .. 1.
sysid::StateSpace siso_system() {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2, 2), B(2, 1), C(1, 2), D(1, 1);
  resonance(A, 0, 100.0, 0.1);
  B << 1.0, 0.0;
  C << 0.1, 0.05;
  D << 0.5;
  return sysid::StateSpace(A, B, C, D, 1.0 / kFs);
}

/// 2 x 2: modes at 80 Hz and 200 Hz, both inputs reach both outputs.
sysid::StateSpace mimo_system() {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4), B(4, 2), C(2, 4), D(2, 2);
  resonance(A, 0, 80.0, 0.08);
  resonance(A, 2, 200.0, 0.1);
  B << 1.0, 0.3, 0.0, 0.0, -0.5, 1.0, 0.0, 0.0;
  C << 0.1, 0.05, 0.08, -0.02, -0.04, 0.1, 0.05, 0.07;
  D << 0.4, 0.1, -0.1, 0.3;
  return sysid::StateSpace(A, B, C, D, 1.0 / kFs);
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

double wrap(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

// White input, white output noise: the true FRF lies inside the 99 % magnitude and
// phase bounds of H1 at >= 95 % of the interior frequencies (expected ~98 %: two 1 %
// tails), and the bound's median width matches B&P's formula with the true coherence.
TEST(SpectralFrf, H1TrueFrfInsideConfidenceBound) {
  const sysid::StateSpace sys = siso_system();
  const Eigen::Index n = 1 << 18;
  const double sn = 1.0;
  const Eigen::MatrixXd u = white_noise(n, 1, 1, 1.0);
  const Eigen::MatrixXd y = sysid::simulate(sys, u) + white_noise(n, 1, 2, sn);
  sysid::FrfOptions o;
  o.welch.nfft = 2048;
  o.confidence = 0.99;
  const sysid::FrfResult r = sysid::frf(u, y, kFs, o);
  ASSERT_EQ(r.freq_hz.size(), 1025);
  const std::vector<Eigen::MatrixXcd> G = sysid::frequency_response(sys, r.freq_hz);
  const double nd = r.dof(0) / 2.0;
  const double z = sysid::normal_quantile(0.995);
  int inside = 0, total = 0;
  std::vector<double> width_ratio;
  for (Eigen::Index k = 1; k + 1 < r.freq_hz.size(); ++k) {
    const auto kk = static_cast<std::size_t>(k);
    const std::complex<double> g = G[kk](0, 0), h = r.H[kk](0, 0);
    const bool mag_ok = r.magnitude_lower[kk](0, 0) <= std::abs(g) && std::abs(g) <= r.magnitude_upper[kk](0, 0);
    const bool phase_ok = std::abs(wrap(std::arg(g) - std::arg(h))) <= r.phase_halfwidth_rad[kk](0, 0);
    inside += (mag_ok && phase_ok) ? 1 : 0;
    ++total;
    const double gamma2 = std::norm(g) / (std::norm(g) + sn * sn);  // white u and n of the same density scale
    const double eps_true = std::sqrt(1.0 - gamma2) / (std::sqrt(gamma2) * std::sqrt(2.0 * nd));
    width_ratio.push_back((r.magnitude_upper[kk](0, 0) - r.magnitude_lower[kk](0, 0)) / (2.0 * z * eps_true * std::abs(g)));
  }
  EXPECT_GE(inside, 0.95 * total) << inside << " of " << total;
  // Not absurdly wide nor narrow: the median estimated width is within 15 % of theory
  // (coherence and |H| estimates scatter by ~eps ~ 5 % per bin; the median is tighter).
  EXPECT_NEAR(median(width_ratio), 1.0, 0.15);
  EXPECT_EQ(r.segments.front(), 255);
  EXPECT_TRUE(std::none_of(r.ill_conditioned.begin(), r.ill_conditioned.end(), [](bool b) { return b; }));
}

// Noise-free: coherence ~ 1 up to the resolution bias at the resonance: the Hann
// window's bandwidth Be = 1.5 fs/nfft = 0.73 Hz against the half-power bandwidth
// Br = 2 zeta f0 = 20 Hz gives 1 - gamma^2 of order (Be/Br)^2 = 1.3e-3 (B&P sec. 9.2.2);
// the threshold 0.995 leaves a factor ~4. In the antiresonance notch (|G| < 0.15,
// 127-141 Hz) the same smoothing acts on a tiny |G|: there only gamma^2 > 0.95 is required. With output noise: gamma^2 = |G|^2 / (|G|^2 + sn^2), and the
// estimate scatters by sqrt(2) (1 - gamma^2) |gamma| / sqrt(n_d) with bias (1 - gamma^2)^2 / n_d
// (B&P Table 9.6): >= 95 % of the bins within 3 s.d. + bias.
TEST(SpectralFrf, CoherenceFollowsTheory) {
  const sysid::StateSpace sys = siso_system();
  const Eigen::Index n = 1 << 18;
  const Eigen::MatrixXd u = white_noise(n, 1, 3, 1.0);
  const Eigen::MatrixXd y0 = sysid::simulate(sys, u);
  sysid::FrfOptions o;
  o.welch.nfft = 2048;
  const sysid::FrfResult clean = sysid::frf(u, y0, kFs, o);
  for (Eigen::Index k = 1; k + 1 < clean.freq_hz.size(); ++k) {
    const double g = std::abs(sysid::frequency_response(sys, clean.freq_hz.segment(k, 1)).front()(0, 0));
    ASSERT_GT(clean.coherence[static_cast<std::size_t>(k)](0, 0), g > 0.15 ? 0.995 : 0.95) << "f = " << clean.freq_hz(k);
    // SISO: the multiple coherence is the ordinary coherence.
    ASSERT_NEAR(clean.multiple_coherence(k, 0), clean.coherence[static_cast<std::size_t>(k)](0, 0), 1e-10);
  }
  const double sn = 0.6;
  const sysid::FrfResult noisy = sysid::frf(u, Eigen::MatrixXd(y0 + white_noise(n, 1, 4, sn)), kFs, o);
  const std::vector<Eigen::MatrixXcd> G = sysid::frequency_response(sys, noisy.freq_hz);
  const double nd = noisy.dof(0) / 2.0;
  int ok = 0, total = 0;
  double lowest = 1.0;
  for (Eigen::Index k = 1; k + 1 < noisy.freq_hz.size(); ++k) {
    const double g2 = std::norm(G[static_cast<std::size_t>(k)](0, 0));
    const double gamma2 = g2 / (g2 + sn * sn);
    lowest = std::min(lowest, gamma2);
    const double sd = std::sqrt(2.0) * (1.0 - gamma2) * std::sqrt(gamma2) / std::sqrt(nd);
    const double bias = (1.0 - gamma2) * (1.0 - gamma2) / nd;
    ok += std::abs(noisy.coherence[static_cast<std::size_t>(k)](0, 0) - gamma2) <= 3.0 * sd + bias ? 1 : 0;
    ++total;
  }
  EXPECT_LT(lowest, 0.5);  // the noise really lowers the coherence somewhere
  EXPECT_GE(ok, 0.95 * total) << ok << " of " << total;
}

// Noise on the measured input only: H2 = Gyy/Gyu is unbiased, while H1 is biased by
// Guu_true / (Guu_true + Gmm) = 1 / (1 + sm^2) for white u and white measurement noise.
TEST(SpectralFrf, H2UnbiasedWithInputNoise) {
  const sysid::StateSpace sys = siso_system();
  const Eigen::Index n = 1 << 17;
  const double sm = 0.5;
  const Eigen::MatrixXd u = white_noise(n, 1, 5, 1.0);
  const Eigen::MatrixXd y = sysid::simulate(sys, u);
  const Eigen::MatrixXd um = u + white_noise(n, 1, 6, sm);
  sysid::FrfOptions o;
  o.welch.nfft = 1024;
  o.estimator = sysid::FrfEstimator::h2;
  const sysid::FrfResult h2 = sysid::frf(um, y, kFs, o);
  o.estimator = sysid::FrfEstimator::h1;
  const sysid::FrfResult h1 = sysid::frf(um, y, kFs, o);
  const std::vector<Eigen::MatrixXcd> G = sysid::frequency_response(sys, h2.freq_hz);
  double r1 = 0.0, r2 = 0.0;
  int cnt = 0;
  for (Eigen::Index k = 5; k + 5 < h2.freq_hz.size(); ++k) {
    const auto kk = static_cast<std::size_t>(k);
    r1 += std::abs(h1.H[kk](0, 0)) / std::abs(G[kk](0, 0));
    r2 += std::abs(h2.H[kk](0, 0)) / std::abs(G[kk](0, 0));
    ++cnt;
  }
  // Averages over ~500 bins of ratios with per-bin random error ~ 3 %: s.d. of the mean < 0.3 %.
  EXPECT_NEAR(r2 / cnt, 1.0, 0.01);
  EXPECT_NEAR(r1 / cnt, 1.0 / (1.0 + sm * sm), 0.01);
}

double max_relative_error(const sysid::FrfResult& r, const sysid::StateSpace& sys) {
  const std::vector<Eigen::MatrixXcd> G = sysid::frequency_response(sys, r.freq_hz);
  double worst = 0.0;
  for (Eigen::Index k = 1; k + 1 < r.freq_hz.size(); ++k) {
    const auto kk = static_cast<std::size_t>(k);
    worst = std::max(worst, (r.H[kk] - G[kk]).norm() / G[kk].norm());
  }
  return worst;
}

// 2 x 2 noise-free: simultaneous independent white inputs (one experiment) and
// one-input-at-a-time (two experiments) both give the true FRF matrix up to the
// resolution bias at the 80 Hz mode: (Be/Br)^2 = (0.73 Hz / 12.8 Hz)^2 = 3e-3 with
// nfft = 2048; 1 % leaves a factor 3.
TEST(SpectralFrf, MimoSimultaneousAndOneAtATime) {
  const sysid::StateSpace sys = mimo_system();
  const Eigen::Index n = 1 << 18;
  sysid::FrfOptions o;
  o.welch.nfft = 2048;
  const Eigen::MatrixXd u = white_noise(n, 2, 7, 1.0);
  const sysid::FrfResult sim = sysid::frf(u, sysid::simulate(sys, u), kFs, o);
  EXPECT_LT(max_relative_error(sim, sys), 0.01);
  EXPECT_TRUE(sim.warnings.empty()) << sim.brief_report();
  EXPECT_EQ(sim.segments[0], 255);
  // Independent white inputs: the condition of G_uu is 1 + O(1/sqrt(n_d)) ~ 1.2.
  EXPECT_LT(sim.input_condition.segment(1, sim.freq_hz.size() - 2).maxCoeff(), 2.0);
  const double nd = sim.dof(0) / 2.0;
  for (Eigen::Index k = 1; k + 1 < sim.freq_hz.size(); ++k) {
    const auto kk = static_cast<std::size_t>(k);
    for (Eigen::Index i = 0; i < 2; ++i) {
      EXPECT_GT(sim.multiple_coherence(k, i), 0.99);  // resolution bias ~3e-3 at the 80 Hz mode
      // Independent inputs: the ordinary coherences add up to the multiple coherence up
      // to a cross term bounded by the chance coherence |gamma_u1u2| of the two inputs,
      // which is Rayleigh with E|gamma|^2 = 1/n_d: below 4/sqrt(n_d) with probability 1 - e^-16.
      EXPECT_NEAR(sim.coherence[kk].row(i).sum(), sim.multiple_coherence(k, i), 4.0 / std::sqrt(nd));
    }
  }

  sysid::IoData data;
  data.Ts = 1.0 / kFs;
  for (Eigen::Index j = 0; j < 2; ++j) {
    Eigen::MatrixXd uj = Eigen::MatrixXd::Zero(n, 2);
    uj.col(j) = white_noise(n, 1, 10 + static_cast<std::uint64_t>(j), 1.0);
    data.add_experiment({uj, sysid::simulate(sys, uj), "exp" + std::to_string(j + 1)});
  }
  const sysid::FrfResult one = sysid::frf_one_at_a_time(data, o);
  EXPECT_LT(max_relative_error(one, sys), 0.01);
  EXPECT_TRUE(one.warnings.empty()) << one.brief_report();
  EXPECT_EQ(one.multiple_coherence.size(), 0);
  EXPECT_EQ(one.segments[0], 255);
  // Pooling both experiments in one MIMO H1 gives the same matrix (G_uu is diagonal-dominant).
  const sysid::FrfResult pooled = sysid::frf(data, o);
  EXPECT_LT(max_relative_error(pooled, sys), 0.01);
  // Explicit mapping gives the same; a wrong mapping (both to input 0) leaves input 1 undriven.
  o.excited_input = {0, 1};
  EXPECT_LT(max_relative_error(sysid::frf_one_at_a_time(data, o), sys), 0.01);
  o.excited_input = {0, 0};
  EXPECT_THROW(sysid::frf_one_at_a_time(data, o), std::invalid_argument);
  o.excited_input = {0, 2};
  EXPECT_THROW(sysid::frf_one_at_a_time(data, o), std::invalid_argument);
  o.excited_input = {0};
  EXPECT_THROW(sysid::frf_one_at_a_time(data, o), std::invalid_argument);
  // The other input not quiet in a one-at-a-time experiment: its column is biased, and a warning says so.
  sysid::IoData leaky;
  leaky.Ts = 1.0 / kFs;
  for (Eigen::Index j = 0; j < 2; ++j) {
    Eigen::MatrixXd uj = 0.5 * white_noise(n, 2, 20 + static_cast<std::uint64_t>(j), 1.0);
    uj.col(j) *= 2.0;
    leaky.add_experiment({uj, sysid::simulate(sys, uj), "leaky"});
  }
  o.excited_input.clear();
  const sysid::FrfResult lr = sysid::frf_one_at_a_time(leaky, o);
  EXPECT_EQ(std::count_if(lr.warnings.begin(), lr.warnings.end(),
                          [](const std::string& w) { return w.find("biased") != std::string::npos; }),
            2);
  // ... while the pooled MIMO H1 handles it exactly.
  EXPECT_LT(max_relative_error(sysid::frf(leaky, o), sys), 0.01);
}

// Hostile inputs: identical input channels make G_uu singular (NaN FRF, flagged);
// nearly identical ones make it ill-conditioned (flagged, finite, warned).
TEST(SpectralFrf, IllConditionedInputsFlagged) {
  const sysid::StateSpace sys = mimo_system();
  const Eigen::Index n = 1 << 14;
  Eigen::MatrixXd u(n, 2);
  u.col(0) = white_noise(n, 1, 30, 1.0);
  u.col(1) = u.col(0);
  sysid::FrfOptions o;
  o.welch.nfft = 256;
  const sysid::FrfResult same = sysid::frf(u, sysid::simulate(sys, u), kFs, o);
  EXPECT_TRUE(std::all_of(same.ill_conditioned.begin(), same.ill_conditioned.end(), [](bool b) { return b; }));
  EXPECT_TRUE(std::isnan(same.H[10](0, 0).real()));
  ASSERT_FALSE(same.warnings.empty());
  EXPECT_NE(same.warnings.front().find("ill-conditioned"), std::string::npos);
  u.col(1) += 1e-5 * white_noise(n, 1, 31, 1.0);  // condition ~ 1 / (1e-5)^2 / 2 ~ 1e10
  const sysid::FrfResult near = sysid::frf(u, sysid::simulate(sys, u), kFs, o);
  EXPECT_GT(near.input_condition(10), 1e8);
  EXPECT_TRUE(near.ill_conditioned[10]);
  EXPECT_TRUE(std::isfinite(near.H[10](0, 0).real()));
  EXPECT_FALSE(near.warnings.empty());
}

// A noise-free system in periodic steady state under a multisine with whole periods:
// the ETFE is exact at every excited bin (no leakage), NaN elsewhere; MIMO from two
// experiments with independent phases.
TEST(SpectralEtfe, ExactForMultisineAtExcitedBins) {
  const Eigen::Index P = 1000;
  sysid::MultisineOptions mo;
  mo.fs_hz = kFs;
  mo.f_min_hz = 5.0;
  mo.f_max_hz = 400.0;
  mo.samples = 4 * P;
  mo.period = P;
  const sysid::StateSpace siso = siso_system();
  const Eigen::MatrixXd u = sysid::multisine(mo);
  sysid::EtfeOptions eo;
  eo.period = P;
  eo.transient_periods = 1;  // the slowest pole has |z| = 0.94: after 1000 samples the transient is ~1e-27
  const sysid::EtfeResult r = sysid::etfe(u, sysid::simulate(siso, u), kFs, eo);
  ASSERT_EQ(r.freq_hz.size(), P / 2 + 1);
  EXPECT_EQ(r.periods, 3);
  const std::vector<Eigen::MatrixXcd> G = sysid::frequency_response(siso, r.freq_hz);
  int excited = 0;
  for (Eigen::Index k = 0; k < r.freq_hz.size(); ++k) {
    const auto kk = static_cast<std::size_t>(k);
    const bool should = r.freq_hz(k) >= 5.0 - 1e-9 && r.freq_hz(k) <= 400.0 + 1e-9;
    ASSERT_EQ(r.excited[kk], should) << "f = " << r.freq_hz(k);
    if (should) {
      ++excited;
      EXPECT_LT(std::abs(r.H[kk](0, 0) - G[kk](0, 0)), 1e-9 * std::abs(G[kk](0, 0)));
    } else {
      EXPECT_TRUE(std::isnan(r.H[kk](0, 0).real()));
    }
  }
  EXPECT_EQ(excited, 396);

  const sysid::StateSpace mimo = mimo_system();
  mo.inputs = 2;
  sysid::IoData data;
  data.Ts = 1.0 / kFs;
  for (std::uint64_t seed : {1u, 2u}) {
    mo.seed = seed;
    const Eigen::MatrixXd ue = sysid::multisine(mo);
    data.add_experiment({ue, sysid::simulate(mimo, ue), "seed" + std::to_string(seed)});
  }
  const sysid::EtfeResult rm = sysid::etfe(data, eo);
  const std::vector<Eigen::MatrixXcd> Gm = sysid::frequency_response(mimo, rm.freq_hz);
  for (Eigen::Index k = 0; k < rm.freq_hz.size(); ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (!rm.excited[kk]) continue;
    // Exact up to rounding amplified by the condition of the 2 x 2 input DFT matrix.
    EXPECT_LT((rm.H[kk] - Gm[kk]).norm(), 1e-12 * std::max(1.0, rm.input_condition(k)) * Gm[kk].norm()) << rm.freq_hz(k);
  }
  // One experiment cannot separate two inputs without smoothing: nothing is excited.
  sysid::IoData single = data;
  single.experiments.pop_back();
  const sysid::EtfeResult rs = sysid::etfe(single, eo);
  EXPECT_TRUE(std::none_of(rs.excited.begin(), rs.excited.end(), [](bool b) { return b; }));
  EXPECT_FALSE(rs.warnings.empty());
}

// Random input with output noise: the raw ETFE has ~100 % scatter where the SNR per
// bin is ~1; Hann smoothing over 2w + 1 = 41 bins averages ~20 independent bins and
// cuts the median error several-fold (G is smooth over 41 bins = 10 Hz at fs/N = 0.24 Hz).
TEST(SpectralEtfe, SmoothingReducesScatter) {
  const sysid::StateSpace sys = siso_system();
  const Eigen::Index n = 4096;
  const Eigen::MatrixXd u = white_noise(n, 1, 40, 1.0);
  const Eigen::MatrixXd y = sysid::simulate(sys, u) + white_noise(n, 1, 41, 0.3);
  sysid::EtfeOptions eo;
  const sysid::EtfeResult raw = sysid::etfe(u, y, kFs, eo);
  eo.smoothing_bins = 20;
  const sysid::EtfeResult smooth = sysid::etfe(u, y, kFs, eo);
  const std::vector<Eigen::MatrixXcd> G = sysid::frequency_response(sys, raw.freq_hz);
  std::vector<double> e_raw, e_smooth;
  for (Eigen::Index k = 25; k + 25 < raw.freq_hz.size(); ++k) {
    const auto kk = static_cast<std::size_t>(k);
    e_raw.push_back(std::abs(raw.H[kk](0, 0) - G[kk](0, 0)) / std::abs(G[kk](0, 0)));
    e_smooth.push_back(std::abs(smooth.H[kk](0, 0) - G[kk](0, 0)) / std::abs(G[kk](0, 0)));
  }
  EXPECT_LT(median(e_smooth), 0.4 * median(e_raw));
}

TEST(SpectralFrf, BadArgumentsThrow) {
  const Eigen::MatrixXd u = white_noise(512, 2, 50, 1.0), y = white_noise(512, 1, 51, 1.0);
  sysid::FrfOptions o;
  o.welch.nfft = 64;
  EXPECT_THROW(sysid::frf(u, y, 0.0, o), std::invalid_argument);
  sysid::FrfOptions bad = o;
  bad.confidence = 1.0;
  EXPECT_THROW(sysid::frf(u, y, kFs, bad), std::invalid_argument);
  bad = o;
  bad.max_condition = 1.0;
  EXPECT_THROW(sysid::frf(u, y, kFs, bad), std::invalid_argument);
  bad = o;
  bad.estimator = sysid::FrfEstimator::h2;  // 2 inputs, 1 output
  EXPECT_THROW(sysid::frf(u, y, kFs, bad), std::invalid_argument);
  bad = o;
  bad.welch.overlap = 1.5;
  EXPECT_THROW(sysid::frf(u, y, kFs, bad), std::invalid_argument);
  EXPECT_THROW(sysid::frf(u, Eigen::MatrixXd(y.topRows(500)), kFs, o), std::invalid_argument);
  EXPECT_THROW(sysid::frf(Eigen::MatrixXd(u.topRows(4)), Eigen::MatrixXd(y.topRows(4)), kFs, o), std::invalid_argument);
  sysid::EtfeOptions eo;
  eo.period = 1;
  EXPECT_THROW(sysid::etfe(u, y, kFs, eo), std::invalid_argument);
  eo.period = 256;
  eo.transient_periods = 2;  // 512 samples hold only 2 periods
  EXPECT_THROW(sysid::etfe(u, y, kFs, eo), std::invalid_argument);
  eo.transient_periods = -1;
  EXPECT_THROW(sysid::etfe(u, y, kFs, eo), std::invalid_argument);
  eo = {};
  eo.excitation_threshold = 1.0;
  EXPECT_THROW(sysid::etfe(u, y, kFs, eo), std::invalid_argument);
  eo = {};
  eo.smoothing_bins = -1;
  EXPECT_THROW(sysid::etfe(u, y, kFs, eo), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_spectral_frf
