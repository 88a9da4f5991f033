// model_output_spectrum: closed forms (AR(1), the input part with coherent inputs),
// Parseval against the Lyapunov variance, agreement with the Welch estimate of a
// simulated process, and spectrum_agreement's figures; bad arguments.
#include <sysid/core/simulate.hpp>
#include <sysid/reduce/gramians.hpp>
#include <sysid/spectral/confidence.hpp>
#include <sysid/spectral/model_spectrum.hpp>
#include <sysid/spectral/welch.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include "random_matrices.hpp"

namespace test_unit_spectral_model_spectrum {

using namespace sysid;

namespace {

using cd = std::complex<double>;
using sysid::test::kPi;

/// AR(1) y(t) = a y(t-1) + e(t) in innovation form: x = y(t-1) ... x+ = a x + a e, y = x + e.
StateSpace ar1(double a, double ts) {
  return StateSpace(Eigen::MatrixXd::Constant(1, 1, a), Eigen::MatrixXd::Zero(1, 0), Eigen::MatrixXd::Ones(1, 1),
                    Eigen::MatrixXd::Zero(1, 0), ts);
}

/// A two-mode innovation model (one output) with a stable, lightly damped A.
struct TwoMode {
  StateSpace model;
  Eigen::MatrixXd K;
};
TwoMode two_mode(double ts) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4);
  const auto block = [&](Eigen::Index i, double f, double zeta) {
    const double w = 2 * kPi * f, r = std::exp(-zeta * w * ts), th = w * std::sqrt(1 - zeta * zeta) * ts;
    A.block(i, i, 2, 2) << r * std::cos(th), r * std::sin(th), -r * std::sin(th), r * std::cos(th);
  };
  block(0, 40.0, 0.03);
  block(2, 110.0, 0.08);
  Eigen::MatrixXd K(4, 1);
  K << 0.3, -0.2, 0.5, 0.1;
  Eigen::MatrixXd C(1, 4);
  C << 1.0, 0.4, -0.7, 1.2;
  return {StateSpace(A, Eigen::MatrixXd::Zero(4, 0), C, Eigen::MatrixXd::Zero(1, 0), ts), K};
}

}  // namespace

TEST(ModelSpectrum, Ar1MatchesTheClosedForm) {
  const double a = 0.8, ts = 0.01, lambda = 2.5;
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(51, 0.0, 50.0);
  const ModelSpectrum s = model_output_spectrum(ar1(a, ts), Eigen::MatrixXd::Constant(1, 1, a), Eigen::MatrixXd::Constant(1, 1, lambda), f);
  ASSERT_EQ(s.output_psd.rows(), 51);
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    // Phi(f) = c Ts lambda / |1 - a e^{-j w Ts}|^2, c = 1 at DC and Nyquist, 2 between.
    const double c = (k == 0 || k == f.size() - 1) ? 1.0 : 2.0;
    const double expected = c * ts * lambda / std::norm(1.0 - a * std::exp(cd(0, -2 * kPi * f(k) * ts)));
    EXPECT_NEAR(s.output_psd(k, 0), expected, 1e-12 * expected) << f(k);
    EXPECT_EQ(s.output_psd(k, 0), s.disturbance_psd(k, 0));
  }
  EXPECT_TRUE(s.warnings.empty());
  // An unstable AR(1) has no stationary output: said so.
  const ModelSpectrum u = model_output_spectrum(ar1(1.1, ts), Eigen::MatrixXd::Constant(1, 1, 1.1), Eigen::MatrixXd::Constant(1, 1, lambda), f);
  ASSERT_EQ(u.warnings.size(), 1u);
  EXPECT_NE(u.warnings[0].find("unstable"), std::string::npos) << u.warnings[0];
}

TEST(ModelSpectrum, IntegratesToTheLyapunovVariance) {
  // Parseval: the one-sided density integrated over 0..fs/2 is var(y) = C P C^T + lambda,
  // P = A P A^T + K lambda K^T.
  const double ts = 1e-3, lambda = 0.7;
  const TwoMode m = two_mode(ts);
  const Eigen::MatrixXd L = controllability_gramian_factor(m.model.A, m.K * std::sqrt(lambda), true);
  const double variance = (m.model.C * L * L.transpose() * m.model.C.transpose())(0, 0) + lambda;
  const Eigen::Index bins = 200001;  // fine enough for the 40 Hz peak's half-power width of 2.4 Hz
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(bins, 0.0, 0.5 / ts);
  const ModelSpectrum s = model_output_spectrum(m.model, m.K, Eigen::MatrixXd::Constant(1, 1, lambda), f);
  // The DC and Nyquist bins carry half weight already: a plain sum times df is the
  // trapezoidal rule of the two-sided density over -fs/2..fs/2.
  const double df = f(1) - f(0);
  EXPECT_NEAR(s.output_psd.col(0).sum() * df, variance, 1e-6 * variance);
}

TEST(ModelSpectrum, InputPartUsesTheCrossSpectraWithTheirPhase) {
  // Phi_y = G S^T G^H with S(i, j) = E[conj(U_i) U_j] (welch_csd's convention).
  // Static gains G = [1, +-1] and u2 = -u1 (S12 = S21 = -1): cancel, or double the amplitude.
  const StateSpace plus(Eigen::MatrixXd::Zero(0, 0), Eigen::MatrixXd::Zero(0, 2), Eigen::MatrixXd::Zero(1, 0),
                        (Eigen::MatrixXd(1, 2) << 1.0, 1.0).finished(), 0.01);
  StateSpace minus = plus;
  minus.D(0, 1) = -1.0;
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(3, 0.0, 50.0);
  const std::vector<Eigen::MatrixXcd> S(3, (Eigen::MatrixXcd(2, 2) << 1.0, -1.0, -1.0, 1.0).finished());
  EXPECT_NEAR(model_output_spectrum(plus, {}, {}, f, S).output_psd.maxCoeff(), 0.0, 1e-15);
  EXPECT_NEAR(model_output_spectrum(minus, {}, {}, f, S).output_psd.minCoeff(), 4.0, 1e-14);
  // Complex cross-spectra: u2 = j u1 (S12 = j, S21 = -j) through y(t) = u1(t) + u2(t - 1),
  // G(z) = [1, z^-1] = [1, -j] at f = fs/4: y = u1 - j j u1 = 2 u1, Phi = 4 (S untransposed
  // would give 0).
  const double ts = 0.01;
  const StateSpace delay(Eigen::MatrixXd::Zero(1, 1), (Eigen::MatrixXd(1, 2) << 0.0, 1.0).finished(), Eigen::MatrixXd::Ones(1, 1),
                         (Eigen::MatrixXd(1, 2) << 1.0, 0.0).finished(), ts);
  const Eigen::MatrixXcd Sj = (Eigen::MatrixXcd(2, 2) << 1.0, cd(0, 1), cd(0, -1), 1.0).finished();
  const ModelSpectrum s = model_output_spectrum(delay, {}, {}, Eigen::VectorXd::Constant(1, 0.25 / ts), {Sj});
  EXPECT_NEAR(s.output_psd(0, 0), 4.0, 1e-12);
  EXPECT_EQ(s.disturbance_psd(0, 0), 0.0);
}

TEST(ModelSpectrum, AgreesWithTheWelchEstimateOfASimulatedProcess) {
  const double ts = 1e-3, lambda = 0.7;
  const TwoMode m = two_mode(ts);
  const Eigen::Index n = 200000;
  std::mt19937_64 rng(17);
  std::normal_distribution<double> g(0.0, std::sqrt(lambda));
  Eigen::MatrixXd e(n, 1);
  for (Eigen::Index t = 0; t < n; ++t) e(t, 0) = g(rng);
  // y = C x + e, x+ = A x + K e: simulate the innovation model with e as its input.
  const StateSpace innovation(m.model.A, m.K, m.model.C, Eigen::MatrixXd::Ones(1, 1), ts);
  const Eigen::MatrixXd y = simulate(innovation, e);
  WelchOptions o;
  o.nfft = 2048;
  const PowerSpectrum ps = welch_psd(y, 1.0 / ts, o);
  const ModelSpectrum s = model_output_spectrum(m.model, m.K, Eigen::MatrixXd::Constant(1, 1, lambda), ps.freq_hz);
  const auto [lo, hi] = psd_confidence_factors(ps.dof, 0.95);
  const SpectrumAgreement a = spectrum_agreement(ps.psd.col(0), s.output_psd.col(0), ps.freq_hz, 1.0, 499.0, lo, hi);
  EXPECT_GT(a.bins, 1000);  // df = fs / nfft = 0.49 Hz
  EXPECT_LT(std::abs(a.median_db), 0.2);
  EXPECT_LT(a.mean_abs_db, 0.5);
  // ~195 segments: 95 % bounds should hold the truth in ~95 % of the bins
  // (the Hann window's leakage at the 40 Hz peak costs a few bins).
  EXPECT_GT(a.fraction_inside, 0.9);
  // A model with the 40 Hz mode 5 % off is visibly worse.
  TwoMode off = two_mode(ts);
  const double w = 2 * kPi * 42.0, r = std::exp(-0.03 * w * ts), th = w * std::sqrt(1 - 0.03 * 0.03) * ts;
  off.model.A.block(0, 0, 2, 2) << r * std::cos(th), r * std::sin(th), -r * std::sin(th), r * std::cos(th);
  const SpectrumAgreement b = spectrum_agreement(ps.psd.col(0), model_output_spectrum(off.model, off.K, Eigen::MatrixXd::Constant(1, 1, lambda), ps.freq_hz).output_psd.col(0),
                                                 ps.freq_hz, 30.0, 50.0, lo, hi);
  EXPECT_LT(b.fraction_inside, 0.5);
  EXPECT_GT(b.mean_abs_db, 2.0);
}

TEST(SpectrumAgreement, FiguresOfAKnownOffset) {
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(101, 0.0, 100.0);
  Eigen::VectorXd estimate = Eigen::VectorXd::Ones(101), model = Eigen::VectorXd::Constant(101, std::pow(10.0, 0.1));
  // One decibel high everywhere; half the bins made 3 dB low instead.
  for (Eigen::Index k = 0; k < 101; k += 2) model(k) = std::pow(10.0, -0.3);
  const SpectrumAgreement a = spectrum_agreement(estimate, model, f, 1.0, 100.0, 0.8, 1.3);
  EXPECT_EQ(a.bins, 100);
  EXPECT_NEAR(a.mean_abs_db, 2.0, 1e-12);
  EXPECT_NEAR(a.median_db, -1.0, 1e-12);  // 50 bins at -3 dB, 50 at +1 dB: the middle pair's mean
  EXPECT_NEAR(a.fraction_inside, 0.5, 1e-12);  // 10^0.1 = 1.26 < 1.3 inside; 10^-0.3 = 0.5 outside
  EXPECT_THROW(spectrum_agreement(estimate, model, f, 200.0, 300.0, 0.8, 1.3), std::invalid_argument);
  EXPECT_THROW(spectrum_agreement(estimate, model.head(5), f, 1.0, 100.0, 0.8, 1.3), std::invalid_argument);
  EXPECT_THROW(spectrum_agreement(estimate, model, f, 1.0, 100.0, 1.2, 1.3), std::invalid_argument);
}

TEST(ModelSpectrum, RefusesWhatHasNoSpectrum) {
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(5, 0.0, 50.0);
  const Eigen::MatrixXd one = Eigen::MatrixXd::Ones(1, 1);
  // No inputs and no disturbance model.
  EXPECT_THROW(model_output_spectrum(ar1(0.5, 0.01), {}, {}, f), std::invalid_argument);
  // Continuous model.
  EXPECT_THROW(model_output_spectrum(ar1(-1.0, 0.0), one, one, f), std::invalid_argument);
  // K of the wrong size; a negative variance; frequencies beyond Nyquist.
  EXPECT_THROW(model_output_spectrum(ar1(0.5, 0.01), Eigen::MatrixXd::Ones(2, 1), one, f), std::invalid_argument);
  EXPECT_THROW(model_output_spectrum(ar1(0.5, 0.01), one, -one, f), std::invalid_argument);
  EXPECT_THROW(model_output_spectrum(ar1(0.5, 0.01), one, one, Eigen::VectorXd::Constant(1, 60.0)), std::invalid_argument);
}

}  // namespace test_unit_spectral_model_spectrum
