// Tests of diagnose/mismatch_location.hpp: a correct nominal model raises no alarm,
// and each kind of mismatch is found by the family meant for it, at the right
// frequency, time, amplitude or position.
//
// Set-up: Ts = 0.5 ms (fs = 2 kHz), N = 20000, so nfft = 2048 (bin 0.977 Hz) and
// about 18 Welch averages. Nominal model: a lightly damped resonator (15 Hz,
// zeta 0.05, unit DC gain) driven by white noise; y_nom = simulate(nominal, u).
#include <sysid/core/simulate.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/diagnose/mismatch_location.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace test_unit_diagnose_mismatch_location {

namespace {

constexpr double kTs = 0.5e-3;
constexpr Eigen::Index kN = 20000;

/// Resonator f0 / zeta with unit DC gain, as a 2-state discrete model (poles r e^{+-i th}).
sysid::StateSpace resonator(double f0, double zeta, double dc_gain) {
  const double w0 = 2.0 * std::numbers::pi * f0;
  const double r = std::exp(-zeta * w0 * kTs), th = w0 * kTs * std::sqrt(1.0 - zeta * zeta);
  Eigen::MatrixXd A(2, 2), B(2, 1), C(1, 2), D(1, 1);
  A << 2.0 * r * std::cos(th), -r * r, 1.0, 0.0;
  B << 1.0, 0.0;
  C << dc_gain * (1.0 - 2.0 * r * std::cos(th) + r * r), 0.0;  // x1 has DC gain 1 / (1 - a1 - a2)
  D << 0.0;
  return sysid::StateSpace(A, B, C, D, kTs);
}

Eigen::VectorXd white(Eigen::Index n, double sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, sigma);
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) x(k) = g(rng);
  return x;
}

/// AR(1) noise e_t = a e_{t-1} + w_t scaled to standard deviation sigma.
Eigen::VectorXd ar1(Eigen::Index n, double a, double sigma, std::mt19937_64& rng) {
  Eigen::VectorXd w = white(n, sigma * std::sqrt(1.0 - a * a), rng);
  Eigen::VectorXd e(n);
  e(0) = w(0) / std::sqrt(1.0 - a * a);
  for (Eigen::Index k = 1; k < n; ++k) e(k) = a * e(k - 1) + w(k);
  return e;
}

struct Case {
  Eigen::MatrixXd u, y_nom, y, r;
};

/// u white (sigma 1), y_nom from the nominal resonator, y = y_nom + extra.
Case make_case(const Eigen::VectorXd& u, const Eigen::VectorXd& extra) {
  Case c;
  c.u = u;
  c.y_nom = sysid::simulate(resonator(15.0, 0.05, 1.0), c.u);
  c.r = extra;
  c.y = c.y_nom + c.r;
  return c;
}

sysid::MismatchLocation run(const Case& c, const sysid::MismatchLocationOptions& o = {}) {
  return sysid::locate_mismatch(c.u, c.y, c.r, c.y_nom, kTs, o);
}

bool has(const sysid::MismatchLocation& loc, const std::string& fired) {
  return std::find(loc.fired.begin(), loc.fired.end(), fired) != loc.fired.end();
}

// ---------------------------------------------------------------------------

// A correct nominal model: residual = measurement noise independent of u, white or
// coloured (AR(1), pole 0.95: correlation time 20 samples). The family-wise level is
// 1 % per run and the families are Bonferroni-combined, so each run raises a false
// alarm with probability <= 1 % (measured offline, 1000-2000 runs each: 0.55 % white,
// 0.60 % AR(1) 0.95, 0.30 % AR(1) 0.99, 0.9 % with two inputs). Over 40 independent runs, >= 2 alarms would have probability
// <= 1 - 0.99^40 - 40 (0.01) 0.99^39 = 6 % at the nominal rate and ~2 % at the
// measured one; the seeds are fixed, so the test is deterministic.
TEST(MismatchLocation, CorrectModelRaisesNoAlarm) {
  int alarms = 0, runs = 0;
  std::string why;
  for (int colour = 0; colour < 2; ++colour)
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      std::mt19937_64 rng(1000 * colour + seed);
      const Eigen::VectorXd u = white(kN, 1.0, rng);
      const Eigen::VectorXd e = colour ? ar1(kN, 0.95, 0.05, rng) : white(kN, 0.05, rng);
      const sysid::MismatchLocation loc = run(make_case(u, e));
      ++runs;
      ASSERT_EQ(loc.outputs.size(), 1u);
      const auto& ch = loc.outputs[0];
      // The per-family verdicts agree with the overall one.
      const bool any = !ch.bands.empty() || !ch.peaks.empty() || ch.amplitude.flagged || ch.reversal.flagged ||
                       ch.position.flagged || ch.offset.flagged || ch.asymmetry.flagged ||
                       std::any_of(ch.windows.begin(), ch.windows.end(), [](const auto& w) { return w.flagged; });
      EXPECT_EQ(any, loc.any_mismatch);
      EXPECT_TRUE(ch.amplitude.tested && ch.reversal.tested && ch.position.tested && ch.asymmetry.tested);
      EXPECT_EQ(ch.asymmetry.regressors, 2);  // u^2 and |u|
      if (loc.any_mismatch) {
        ++alarms;
        why += loc.brief_report() + "\n";
      }
    }
  EXPECT_EQ(runs, 40);
  EXPECT_LE(alarms, 1) << why;
}

// The statistics behind the verdicts are calibrated (not just conservative to the
// point of blindness): under the null the amplitude z and the reversal sign z are
// ~N(0,1), so over 20 runs their RMS must lie in [0.6, 1.5] (the RMS of 20 standard
// normals is in [0.68, 1.3] with probability > 99.9 %; margin for the Welch variance
// estimate's own ~25 % scatter).
TEST(MismatchLocation, NullStatisticsAreStandardised) {
  double s_amp = 0.0, s_sign = 0.0, s_energy = 0.0;
  const int runs = 20;
  for (int seed = 0; seed < runs; ++seed) {
    std::mt19937_64 rng(500 + seed);
    const Eigen::VectorXd u = white(kN, 1.0, rng);
    const sysid::MismatchLocation loc = run(make_case(u, ar1(kN, 0.9, 0.05, rng)));
    const auto& ch = loc.outputs[0];
    s_amp += ch.amplitude.z * ch.amplitude.z;
    s_sign += ch.reversal.sign_z * ch.reversal.sign_z;
    s_energy += ch.reversal.energy_z * ch.reversal.energy_z;
  }
  for (const double s : {s_amp, s_sign, s_energy}) {
    const double rms = std::sqrt(s / runs);
    EXPECT_GT(rms, 0.6);
    EXPECT_LT(rms, 1.5);
  }
}

// A mode at 37 Hz (zeta 0.05, peak gain 0.025 / (2 zeta) = 0.25) the nominal model
// lacks, weak in RMS (~0.019 against 0.05 of noise) but coherent with u near its
// resonance. zeta 0.05 keeps the half-power bandwidth (3.7 Hz) wide against the Hann
// resolution (1.5 bins = 1.46 Hz): the H1 resolution bias -(1/3)(B_e/B_r)^2 (Bendat &
// Piersol sec. 9.2.2) is then ~5 % (with zeta 0.02 it is ~35 %).
TEST(MismatchLocation, MissingModeGivesFalsifiedBand) {
  std::mt19937_64 rng(7);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  const Eigen::VectorXd mode = sysid::simulate(resonator(37.0, 0.05, 0.025), u);
  const sysid::MismatchLocation loc = run(make_case(u, mode + white(kN, 0.05, rng)));
  EXPECT_TRUE(loc.any_mismatch);
  EXPECT_TRUE(has(loc, "model_error:y1"));
  const auto& ch = loc.outputs[0];
  const double bin = 1.0 / (kTs * static_cast<double>(loc.nfft));
  bool found = false;
  for (const auto& b : ch.bands)
    if (b.lo_hz <= 37.0 + bin && b.hi_hz >= 37.0 - bin) {
      found = true;
      // The peak of |E|^2 S_uu (white u: of |E|) is within one bin of 37 Hz.
      EXPECT_NEAR(b.peak_hz, 37.0, bin);
      // |E| at the peak: 0.25 less the ~5 % resolution bias; random error of |H1| at
      // coherence ~0.9 with n_d ~ 17 is ~6 %: 20 % covers both with margin.
      EXPECT_NEAR(b.peak_gain, 0.25, 0.05);
      EXPECT_GT(b.peak_coherence, ch.coherence_threshold);
    }
  EXPECT_TRUE(found) << loc.brief_report();
  // Bands only where the mode's response is within ~10 dB of the noise
  // (|E|^2 S_uu / S_nn > 0.1 between ~17 and ~65 Hz); the nominal part is exact.
  for (const auto& b : ch.bands) {
    EXPECT_GT(b.lo_hz, 15.0) << loc.brief_report();
    EXPECT_LT(b.hi_hz, 70.0) << loc.brief_report();
  }
  // A linear mismatch does not fire the nonlinearity families.
  EXPECT_FALSE(ch.amplitude.flagged || ch.reversal.flagged || ch.position.flagged || ch.asymmetry.flagged)
      << loc.brief_report();
  // The mode is coherent with u: it is not reported as a disturbance peak.
  for (const auto& p : ch.peaks) EXPECT_GT(std::abs(p.freq_hz - 37.0), 3.0) << loc.brief_report();
}

// Two inputs; the missing mode is driven by the second one only.
TEST(MismatchLocation, MissingModeOnSecondInputIsAttributed) {
  std::mt19937_64 rng(8);
  Eigen::MatrixXd u(kN, 2);
  u.col(0) = white(kN, 1.0, rng);
  u.col(1) = white(kN, 1.0, rng);
  Case c;
  c.u = u;
  c.y_nom = sysid::simulate(resonator(15.0, 0.05, 1.0), Eigen::MatrixXd(u.col(0)));
  c.r = sysid::simulate(resonator(37.0, 0.02, 0.01), Eigen::MatrixXd(u.col(1))) + white(kN, 0.05, rng);
  c.y = c.y_nom + c.r;
  const sysid::MismatchLocation loc = run(c);
  ASSERT_FALSE(loc.outputs[0].bands.empty()) << loc.brief_report();
  const double bin = 1.0 / (kTs * static_cast<double>(loc.nfft));
  bool found = false;
  for (const auto& b : loc.outputs[0].bands)
    if (std::abs(b.peak_hz - 37.0) <= bin) {
      found = true;
      EXPECT_EQ(b.input, 1);
      EXPECT_EQ(b.input_name, "u2");
    }
  EXPECT_TRUE(found) << loc.brief_report();
}

// Mains hum: a 50 Hz sine with RMS 0.035 below the noise RMS 0.05, independent of u.
TEST(MismatchLocation, HumIsAPeakNotAModelError) {
  std::mt19937_64 rng(11);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  const double A = 0.05, f = 50.0;
  Eigen::VectorXd hum(kN);
  for (Eigen::Index k = 0; k < kN; ++k) hum(k) = A * std::sin(2.0 * std::numbers::pi * f * kTs * static_cast<double>(k) + 0.3);
  const sysid::MismatchLocation loc = run(make_case(u, hum + white(kN, 0.05, rng)));
  EXPECT_TRUE(loc.any_mismatch);
  EXPECT_TRUE(has(loc, "residual_peak:y1"));
  const auto& ch = loc.outputs[0];
  const double bin = 1.0 / (kTs * static_cast<double>(loc.nfft));
  ASSERT_EQ(ch.peaks.size(), 1u) << loc.brief_report();
  // 50 Hz lies 0.2 bin from bin 51; the log-parabola refinement is good to ~0.1 bin for Hann.
  EXPECT_NEAR(ch.peaks[0].freq_hz, f, 0.5 * bin);
  // Amplitude from the integrated main lobe: noise in the 7 bins is ~0.1 % of the sine
  // power; leakage outside +-3 bins is < 0.1 % for Hann: 20 % is generous.
  EXPECT_NEAR(ch.peaks[0].amplitude, A, 0.2 * A);
  EXPECT_GT(ch.peaks[0].prominence_db, 10.0);
  for (const auto& b : ch.bands) EXPECT_FALSE(b.lo_hz <= f + bin && b.hi_hz >= f - bin) << loc.brief_report();
}

// The residual's standard deviation is 1.5x larger (energy 2.25x) in window 7 of 20.
TEST(MismatchLocation, BurstFlagsItsWindow) {
  std::mt19937_64 rng(13);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  Eigen::VectorXd e = white(kN, 0.05, rng);
  const Eigen::Index W = 20, b = 7, s0 = b * kN / W, n = kN / W;
  e.segment(s0, n) *= 1.5;
  const sysid::MismatchLocation loc = run(make_case(u, e));
  EXPECT_TRUE(has(loc, "time_window:y1"));
  const auto& ch = loc.outputs[0];
  ASSERT_EQ(ch.windows.size(), static_cast<std::size_t>(W));
  for (Eigen::Index w = 0; w < W; ++w) EXPECT_EQ(ch.windows[static_cast<std::size_t>(w)].flagged, w == b) << "window " << w;
  EXPECT_NEAR(ch.windows[static_cast<std::size_t>(b)].t0_s, static_cast<double>(s0) * kTs, 1e-12);
  // Energy ratio 2.25 within the window mean square's scatter (sd ~ sqrt(2/1000) = 4.5 %).
  EXPECT_NEAR(ch.windows[static_cast<std::size_t>(b)].energy_ratio, 2.25, 0.3);
}

// Hardening spring seen as a sensor nonlinearity: y = y_nom + c y_nom^3 + noise.
TEST(MismatchLocation, CubicTermIsAmplitudeDependent) {
  std::mt19937_64 rng(17);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  Case c = make_case(u, Eigen::VectorXd::Zero(kN));
  const double k3 = 0.1;
  c.r = k3 * c.y_nom.array().cube().matrix() + white(kN, 0.05, rng);
  c.y = c.y_nom + c.r;
  const sysid::MismatchLocation loc = run(c);
  const auto& A = loc.outputs[0].amplitude;
  EXPECT_TRUE(A.flagged) << loc.brief_report();
  EXPECT_TRUE(has(loc, "amplitude:y1"));
  // Local slope 1 + 3 k3 y^2: larger where |y_nom| is large.
  EXPECT_GT(A.gain_high - A.gain_low, 5.0 * std::hypot(A.gain_high_se, A.gain_low_se));
  EXPECT_GT(A.gain_high, A.gain_low);
  EXPECT_GT(A.rms_ratio, 1.0);
  // The low set sees |y_nom| below its median: the slope there stays near 1.
  EXPECT_NEAR(A.gain_low, 1.0, 0.1);
  // An odd nonlinearity with a symmetric (Gaussian) input is not asymmetry.
  EXPECT_FALSE(loc.outputs[0].asymmetry.flagged) << loc.brief_report();
}

// A relief valve at the actuator: the force is capped from above only, at 1.5
// sigma of the white input (6.7 % of the samples), y = G min(u, 1.5). The cap's
// excess has a mean and an even part that u^2 and |u| carry and u does not; the
// amplitude test, built for symmetric effects, need not see it.
TEST(MismatchLocation, OneSidedCapIsAsymmetric) {
  std::mt19937_64 rng(47);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  Case c = make_case(u, Eigen::VectorXd::Zero(kN));
  const Eigen::VectorXd capped = u.cwiseMin(1.5);
  c.r = sysid::simulate(resonator(15.0, 0.05, 1.0), capped) - c.y_nom + white(kN, 0.05, rng);
  c.y = c.y_nom + c.r;
  const sysid::MismatchLocation loc = run(c);
  const auto& A = loc.outputs[0].asymmetry;
  ASSERT_TRUE(A.tested);
  EXPECT_TRUE(A.flagged) << loc.brief_report();
  EXPECT_TRUE(has(loc, "asymmetry:y1"));
  EXPECT_GT(A.peak_partial_coherence, A.threshold);
  // The capped excess passes the resonator: it is coherent where G carries power.
  EXPECT_LT(A.peak_hz, 60.0) << loc.brief_report();
}

// The same cap symmetric (+-1.5): an odd effect, so the asymmetry test stays
// silent while the mismatch is still found (as a model error near the resonance).
TEST(MismatchLocation, SymmetricCapIsNotAsymmetric) {
  std::mt19937_64 rng(53);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  Case c = make_case(u, Eigen::VectorXd::Zero(kN));
  const Eigen::VectorXd capped = u.cwiseMin(1.5).cwiseMax(-1.5);
  c.r = sysid::simulate(resonator(15.0, 0.05, 1.0), capped) - c.y_nom + white(kN, 0.05, rng);
  c.y = c.y_nom + c.r;
  const sysid::MismatchLocation loc = run(c);
  EXPECT_FALSE(loc.outputs[0].asymmetry.flagged) << loc.brief_report();
  EXPECT_TRUE(loc.any_mismatch) << loc.brief_report();
}

// An input with an offset (a unipolar command, 3 +- 1): the even functions are
// taken about its mean, so the one-sided cap is found as with a zero-mean input
// (about the origin, |u| would be a copy of u and every bin singular).
TEST(MismatchLocation, OneSidedCapIsFoundOnAnOffsetInput) {
  std::mt19937_64 rng(61);
  const Eigen::VectorXd u = (white(kN, 1.0, rng).array() + 3.0).matrix();
  Case c = make_case(u, Eigen::VectorXd::Zero(kN));
  c.r = sysid::simulate(resonator(15.0, 0.05, 1.0), Eigen::MatrixXd(u.cwiseMin(4.5))) - c.y_nom + white(kN, 0.05, rng);
  c.y = c.y_nom + c.r;
  const sysid::MismatchLocation loc = run(c);
  const auto& A = loc.outputs[0].asymmetry;
  ASSERT_TRUE(A.tested);
  EXPECT_EQ(A.regressors, 2);
  EXPECT_TRUE(A.flagged) << loc.brief_report();
}

// A binary input (+-1, as a PRBS) has constant even functions: test 8 cannot run.
TEST(MismatchLocation, BinaryInputCannotTestAsymmetry) {
  std::mt19937_64 rng(59);
  Eigen::VectorXd u = white(kN, 1.0, rng);
  u = u.array().sign().matrix();
  const sysid::MismatchLocation loc = run(make_case(u, white(kN, 0.05, rng)));
  EXPECT_FALSE(loc.outputs[0].asymmetry.tested);
  EXPECT_FALSE(loc.outputs[0].asymmetry.flagged);
  EXPECT_EQ(loc.outputs[0].asymmetry.regressors, 0);
}

// A linear gain error is not amplitude dependence (E[r | y_nom] is linear).
TEST(MismatchLocation, GainErrorIsNotAmplitudeDependence) {
  std::mt19937_64 rng(19);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  Case c = make_case(u, Eigen::VectorXd::Zero(kN));
  c.r = 0.1 * c.y_nom + white(kN, 0.05, rng);
  c.y = c.y_nom + c.r;
  const sysid::MismatchLocation loc = run(c);
  const auto& ch = loc.outputs[0];
  EXPECT_FALSE(ch.amplitude.flagged) << loc.brief_report();
  EXPECT_NEAR(ch.amplitude.gain_low, 1.1, 5.0 * ch.amplitude.gain_low_se + 1e-3);
  EXPECT_NEAR(ch.amplitude.gain_high, 1.1, 5.0 * ch.amplitude.gain_high_se + 1e-3);
  EXPECT_FALSE(ch.position.flagged) << loc.brief_report();  // linear in position: removed before the test
  EXPECT_FALSE(ch.reversal.flagged) << loc.brief_report();  // linear in the motion: partialled out
  EXPECT_FALSE(ch.asymmetry.flagged) << loc.brief_report();  // linear at every frequency: partialled out
  EXPECT_TRUE(has(loc, "model_error:y1"));                   // a gain error is a model error at the resonance
}

// A breakaway pulse against the new direction of motion for 5 samples after every
// reversal of the nominal velocity.
TEST(MismatchLocation, ReversalPulseIsFlagged) {
  std::mt19937_64 rng(23);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  Case c = make_case(u, Eigen::VectorXd::Zero(kN));
  Eigen::VectorXd pulse = Eigen::VectorXd::Zero(kN);
  double prev = 0.0;
  for (Eigen::Index t = 1; t + 1 < kN; ++t) {
    const double v = c.y_nom(t + 1, 0) - c.y_nom(t - 1, 0);
    const double s = v > 0 ? 1.0 : -1.0;
    if (prev != 0.0 && s != prev)
      for (Eigen::Index q = t; q < std::min(kN, t + 5); ++q) pulse(q) = -0.05 * s;
    prev = s;
  }
  c.r = pulse + white(kN, 0.05, rng);
  c.y = c.y_nom + c.r;
  const sysid::MismatchLocation loc = run(c);
  const auto& R = loc.outputs[0].reversal;
  EXPECT_TRUE(R.flagged) << loc.brief_report();
  EXPECT_TRUE(has(loc, "reversal:y1"));
  EXPECT_GT(R.reversals, 100);
  EXPECT_GT(R.energy_ratio, 1.2);
  EXPECT_LT(R.sign_level, 0.0);  // the pulse opposes the new direction of motion
}

// Cogging-like residual periodic in position: r = 0.02 cos(2 pi y_nom / 0.4) + noise.
TEST(MismatchLocation, PositionPeriodicResidualIsFlagged) {
  std::mt19937_64 rng(29);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  Case c = make_case(u, Eigen::VectorXd::Zero(kN));
  c.r = 0.02 * (2.0 * std::numbers::pi * c.y_nom.array() / 0.4).cos().matrix() + white(kN, 0.05, rng);
  c.y = c.y_nom + c.r;
  const sysid::MismatchLocation loc = run(c);
  const auto& P = loc.outputs[0].position;
  EXPECT_TRUE(P.flagged) << loc.brief_report();
  ASSERT_EQ(P.bin_means.size(), 10);
  // Bin centres are increasing; each bin mean is the cosine term averaged over the
  // bin's samples (the decile bins are wide against the 0.4 period, so not the cosine
  // at the centre) plus noise of sd 0.05 / sqrt(2000) = 0.0011: 5 sd = 0.0056.
  std::vector<double> yn(c.y_nom.data(), c.y_nom.data() + kN);
  std::vector<Eigen::Index> order(static_cast<std::size_t>(kN));
  for (Eigen::Index t = 0; t < kN; ++t) order[static_cast<std::size_t>(t)] = t;
  std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return yn[a] < yn[b]; });
  for (Eigen::Index b = 1; b < 10; ++b) EXPECT_GT(P.bin_centres(b), P.bin_centres(b - 1));
  for (Eigen::Index b = 0; b < 10; ++b) {
    double expected = 0.0;
    const Eigen::Index s0 = b * kN / 10, s1 = (b + 1) * kN / 10;
    for (Eigen::Index q = s0; q < s1; ++q)
      expected += 0.02 * std::cos(2.0 * std::numbers::pi * yn[static_cast<std::size_t>(order[static_cast<std::size_t>(q)])] / 0.4);
    expected /= static_cast<double>(s1 - s0);
    EXPECT_NEAR(P.bin_means(b), expected, 0.0056) << "bin " << b;
  }
}

TEST(MismatchLocation, OffsetIsFlagged) {
  std::mt19937_64 rng(31);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  const sysid::MismatchLocation loc = run(make_case(u, (white(kN, 0.05, rng).array() + 0.005).matrix()));
  const auto& O = loc.outputs[0].offset;
  EXPECT_TRUE(O.flagged) << loc.brief_report();
  EXPECT_NEAR(O.offset, 0.005, 4.0 * O.offset_se);
  // White noise: se = sigma / sqrt(N) = 3.5e-4 (Welch variance estimate within 30 %).
  EXPECT_NEAR(O.offset_se, 0.05 / std::sqrt(static_cast<double>(kN)), 0.3 * 0.05 / std::sqrt(static_cast<double>(kN)));
}

TEST(MismatchLocation, MultipleOutputsAreReportedSeparately) {
  std::mt19937_64 rng(37);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  Case c = make_case(u, white(kN, 0.05, rng));
  Eigen::MatrixXd y_nom(kN, 2), r(kN, 2);
  y_nom << c.y_nom, 0.5 * c.y_nom;
  Eigen::VectorXd hum(kN);
  for (Eigen::Index k = 0; k < kN; ++k) hum(k) = 0.05 * std::sin(2.0 * std::numbers::pi * 80.0 * kTs * static_cast<double>(k));
  r << c.r, hum + white(kN, 0.05, rng);
  sysid::MismatchLocationOptions o;
  o.output_names = {"pos", "acc"};
  const sysid::MismatchLocation loc = sysid::locate_mismatch(u, y_nom + r, r, y_nom, kTs, o);
  ASSERT_EQ(loc.outputs.size(), 2u);
  EXPECT_EQ(loc.outputs[1].output, "acc");
  EXPECT_TRUE(loc.outputs[0].peaks.empty());
  ASSERT_EQ(loc.outputs[1].peaks.size(), 1u);
  EXPECT_TRUE(has(loc, "residual_peak:acc"));
  EXPECT_FALSE(has(loc, "residual_peak:pos"));
  EXPECT_NEAR(loc.family_level, 0.01 / 16.0, 1e-15);  // 8 families x 2 outputs
}

TEST(MismatchLocation, BadInputThrows) {
  std::mt19937_64 rng(41);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  const Case c = make_case(u, white(kN, 0.05, rng));
  EXPECT_THROW(sysid::locate_mismatch(Eigen::MatrixXd(c.u.topRows(kN - 1)), c.y, c.r, c.y_nom, kTs), std::invalid_argument);
  EXPECT_THROW(sysid::locate_mismatch(c.u, c.y, Eigen::MatrixXd(c.r.topRows(kN - 1)), c.y_nom, kTs), std::invalid_argument);
  Eigen::MatrixXd bad = c.r;
  bad(100, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sysid::locate_mismatch(c.u, c.y, bad, c.y_nom, kTs), std::invalid_argument);
  bad = c.u;
  bad(5, 0) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(sysid::locate_mismatch(bad, c.y, c.r, c.y_nom, kTs), std::invalid_argument);
  EXPECT_THROW(sysid::locate_mismatch(c.u, c.y, c.r, c.y_nom, 0.0), std::invalid_argument);
  EXPECT_THROW(sysid::locate_mismatch(c.u, c.y, c.r, c.y_nom, -kTs), std::invalid_argument);
  sysid::MismatchLocationOptions o;
  o.nfft = 4096;  // N = 20000 < 8 * 4096
  EXPECT_THROW(sysid::locate_mismatch(c.u, c.y, c.r, c.y_nom, kTs, o), std::invalid_argument);
  o = {};
  o.significance = 0.0;
  EXPECT_THROW(sysid::locate_mismatch(c.u, c.y, c.r, c.y_nom, kTs, o), std::invalid_argument);
  EXPECT_THROW(sysid::locate_mismatch(Eigen::MatrixXd(c.u.topRows(100)), Eigen::MatrixXd(c.y.topRows(100)),
                                      Eigen::MatrixXd(c.r.topRows(100)), Eigen::MatrixXd(c.y_nom.topRows(100)), kTs),
               std::invalid_argument);  // N < 128
}

TEST(MismatchLocation, ZeroResidualIsNoMismatch) {
  std::mt19937_64 rng(43);
  const Eigen::VectorXd u = white(kN, 1.0, rng);
  const sysid::MismatchLocation loc = run(make_case(u, Eigen::VectorXd::Zero(kN)));
  EXPECT_FALSE(loc.any_mismatch);
  EXPECT_FALSE(loc.warnings.empty());
}

}  // namespace

}  // namespace test_unit_diagnose_mismatch_location
