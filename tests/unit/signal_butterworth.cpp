// Tests of signal/butterworth.hpp: poles against the analytic bilinear images of
// the prototype poles, magnitude against the closed-form digital Butterworth law,
// cutoff/passband/stopband behaviour and the state-space form.
#include <sysid/signal/butterworth.hpp>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <vector>
#include "random_matrices.hpp"

namespace test_unit_signal_butterworth {

namespace {

using C = std::complex<double>;
using sysid::BandType;
using sysid::test::kPi;

// Roots of every section denominator a0 z^2 + a1 z + a2 (one root for a first-order section).
std::vector<C> section_poles(const sysid::SecondOrderSections& f) {
  std::vector<C> poles;
  for (Eigen::Index k = 0; k < f.sos.rows(); ++k) {
    const double a0 = f.sos(k, 3), a1 = f.sos(k, 4), a2 = f.sos(k, 5);
    if (a2 == 0.0) {
      poles.emplace_back(-a1 / a0, 0.0);
    } else {
      const C disc = std::sqrt(C(a1 * a1 - 4.0 * a0 * a2, 0.0));
      poles.push_back((-a1 + disc) / (2.0 * a0));
      poles.push_back((-a1 - disc) / (2.0 * a0));
    }
  }
  return poles;
}

// Greedy one-to-one matching; returns the largest distance between matched entries.
double multiset_distance(std::vector<C> a, std::vector<C> b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (const C& x : a) {
    std::size_t best = 0;
    for (std::size_t j = 1; j < b.size(); ++j)
      if (std::abs(b[j] - x) < std::abs(b[best] - x)) best = j;
    worst = std::max(worst, std::abs(b[best] - x));
    b.erase(b.begin() + static_cast<std::ptrdiff_t>(best));
  }
  return worst;
}

// Expected digital poles, written from the textbook definitions independently of the
// header: analog Butterworth poles on a circle, lp->hp / lp->bp substitution, bilinear map.
std::vector<C> expected_poles(int n, BandType type, double f1, double f2, double fs) {
  const double w1 = 2 * fs * std::tan(kPi * f1 / fs);
  const double w2 = 2 * fs * std::tan(kPi * f2 / fs);
  auto z_of = [fs](C s) { return (2 * fs + s) / (2 * fs - s); };
  std::vector<C> z;
  for (int k = 1; k <= n; ++k) {
    // s_k = exp(i pi (2k + n - 1) / (2n)), k = 1..n (left half plane)
    const C p = std::exp(C(0, kPi * (2.0 * k + n - 1) / (2.0 * n)));
    if (type == BandType::lowpass) {
      z.push_back(z_of(w1 * p));
    } else if (type == BandType::highpass) {
      z.push_back(z_of(w1 / p));
    } else {
      // s^2 - (w2 - w1) p s + w1 w2 = 0
      const C b = -(w2 - w1) * p;
      const C c = w1 * w2;
      const C d = std::sqrt(b * b - 4.0 * c);
      z.push_back(z_of((-b + d) / 2.0));
      z.push_back(z_of((-b - d) / 2.0));
    }
  }
  return z;
}

// Closed-form squared magnitude of the bilinear Butterworth design:
// |H|^2 = 1 / (1 + Omega^(2n)) with Omega the prototype frequency of the prewarped
// analog frequency W = 2 fs tan(pi f / fs).
double expected_mag2(int n, BandType type, double f1, double f2, double fs, double f) {
  const double W = 2 * fs * std::tan(kPi * f / fs);
  const double w1 = 2 * fs * std::tan(kPi * f1 / fs);
  const double w2 = 2 * fs * std::tan(kPi * f2 / fs);
  double omega = 0;
  if (type == BandType::lowpass) omega = W / w1;
  if (type == BandType::highpass) omega = w1 / W;
  if (type == BandType::bandpass) omega = (W * W - w1 * w2) / ((w2 - w1) * W);
  return 1.0 / (1.0 + std::pow(std::abs(omega), 2.0 * n));
}

struct Case {
  int order;
  BandType type;
  double f1, f2, fs;
};

const std::vector<Case> kCases = {
    {5, BandType::lowpass, 100, 0, 2000},  // the Par2 paper's anti-aliasing filter
    {1, BandType::lowpass, 50, 0, 1000},    {2, BandType::lowpass, 300, 0, 1000},
    {8, BandType::lowpass, 5, 0, 1000},     {1, BandType::highpass, 20, 0, 1000},
    {4, BandType::highpass, 200, 0, 1000},  {7, BandType::highpass, 0.5, 0, 100},
    {1, BandType::bandpass, 10, 40, 500},   {2, BandType::bandpass, 45, 55, 1000},
    {5, BandType::bandpass, 100, 400, 1000}, {6, BandType::bandpass, 1, 2, 1000},
};

TEST(SignalButterworth, AnalogPrototypePolesGiveButterworthMagnitude) {
  for (int n = 1; n <= 12; ++n) {
    const Eigen::VectorXcd p = sysid::butterworth_analog_poles(n);
    ASSERT_EQ(p.size(), n);
    for (int k = 0; k < n; ++k) {
      EXPECT_NEAR(std::abs(p(k)), 1.0, 1e-15);
      EXPECT_LT(p(k).real(), 0.0);
      // conjugate symmetry k <-> n-1-k keeps the real polynomial real
      EXPECT_NEAR(std::abs(p(k) - std::conj(p(n - 1 - k))), 0.0, 1e-15);
    }
    // |1 / prod (jw - p_k)|^2 = 1 / (1 + w^(2n)) for the normalised prototype.
    for (double w : {0.0, 0.3, 1.0, 1.7, 10.0}) {
      C h(1, 0);
      for (int k = 0; k < n; ++k) h /= (C(0, w) - p(k));
      EXPECT_NEAR(std::norm(h), 1.0 / (1.0 + std::pow(w, 2.0 * n)), 1e-13) << "n=" << n << " w=" << w;
    }
  }
}

TEST(SignalButterworth, PolesAreBilinearImagesOfPrototypePoles) {
  for (const Case& c : kCases) {
    const auto f = sysid::butterworth(c.order, c.type, c.f1, c.f2, c.fs);
    const auto got = section_poles(f);
    const auto want = expected_poles(c.order, c.type, c.f1, c.f2, c.fs);
    // Both sides are O(1) numbers computed in a few flops each: rounding ~1e-15;
    // 1e-11 leaves room for the quadratic-root formula's cancellation near z = 1.
    EXPECT_LT(multiset_distance(got, want), 1e-11) << "order " << c.order << " f1 " << c.f1;
    for (const C& z : got) EXPECT_LT(std::abs(z), 1.0);
    const Eigen::Index expected_sections = c.type == BandType::bandpass ? c.order : (c.order + 1) / 2;
    EXPECT_EQ(f.sos.rows(), expected_sections);
    for (Eigen::Index k = 0; k < f.sos.rows(); ++k) EXPECT_EQ(f.sos(k, 3), 1.0);
  }
}

TEST(SignalButterworth, MagnitudeFollowsClosedFormLaw) {
  for (const Case& c : kCases) {
    const auto f = sysid::butterworth(c.order, c.type, c.f1, c.f2, c.fs);
    for (int i = 1; i < 400; ++i) {
      const double fr = 0.5 * c.fs * i / 400.0;
      const double got = std::norm(sysid::sos_frequency_response(f, fr));
      EXPECT_NEAR(got, expected_mag2(c.order, c.type, c.f1, c.f2, c.fs, fr), 1e-10)
          << "order " << c.order << " f1 " << c.f1 << " at " << fr << " Hz";
    }
  }
}

TEST(SignalButterworth, CutoffIsMinus3dBAndPassbandGainIsOne) {
  const double half = 1.0 / std::sqrt(2.0);
  for (const Case& c : kCases) {
    const auto f = sysid::butterworth(c.order, c.type, c.f1, c.f2, c.fs);
    // A biquad denominator near z = 1 is a difference of O(1) terms equal to about
    // |1 - p|^2 ~ (2 pi f/fs)^2, so each section's response carries a relative
    // round-off of eps / (2 pi f/fs)^2 at low f: e.g. 1e-12 per section at 1 Hz, fs 1 kHz.
    const double w = 2 * kPi * std::min(c.f1, 0.5 * c.fs - (c.type == BandType::bandpass ? c.f2 : c.f1)) / c.fs;
    const double tol = std::max(1e-12, 10.0 * c.order * 2.2e-16 / (w * w));
    EXPECT_NEAR(std::abs(sysid::sos_frequency_response(f, c.f1)), half, tol);
    if (c.type == BandType::lowpass) {
      const C dc = sysid::sos_frequency_response(f, 0.0);
      EXPECT_NEAR(dc.real(), 1.0, 1e-13);  // real and positive: no sign flip
      EXPECT_NEAR(dc.imag(), 0.0, 1e-13);
    } else if (c.type == BandType::highpass) {
      EXPECT_NEAR(std::abs(sysid::sos_frequency_response(f, 0.5 * c.fs)), 1.0, 1e-13);
      EXPECT_NEAR(std::abs(sysid::sos_frequency_response(f, 0.0)), 0.0, 1e-13);
    } else {
      EXPECT_NEAR(std::abs(sysid::sos_frequency_response(f, c.f2)), half, tol);
      const double w0 = 2 * c.fs * std::sqrt(std::tan(kPi * c.f1 / c.fs) * std::tan(kPi * c.f2 / c.fs));
      const double fc = c.fs / kPi * std::atan(w0 / (2 * c.fs));
      EXPECT_NEAR(std::abs(sysid::sos_frequency_response(f, fc)), 1.0, tol);
      EXPECT_NEAR(std::abs(sysid::sos_frequency_response(f, 0.0)), 0.0, 1e-13);
      EXPECT_NEAR(std::abs(sysid::sos_frequency_response(f, 0.5 * c.fs)), 0.0, 1e-13);
    }
  }
}

TEST(SignalButterworth, StopbandRollOffIsTwentyDbPerDecadePerOrder) {
  // fc = 10 Hz at fs = 10 kHz: over the decade 100 Hz -> 1 kHz the analog law falls by
  // 10 log10((1 + 100^(2n)) / (1 + 10^(2n))) ~ 20 n dB; frequency warping makes the
  // digital filter steeper by at most 20 n log10(tan(0.1 pi)/(0.1 pi)) = 0.29 n dB.
  for (int n = 1; n <= 8; ++n) {
    const auto lp = sysid::butterworth(n, BandType::lowpass, 10, 0, 10000);
    const double drop =
        20 * std::log10(std::abs(sysid::sos_frequency_response(lp, 100)) / std::abs(sysid::sos_frequency_response(lp, 1000)));
    EXPECT_GT(drop, 20.0 * n - 0.05) << n;
    EXPECT_LT(drop, 20.0 * n + 0.3 * n) << n;
    // Highpass mirror: 1 kHz cutoff, decade 100 Hz -> 10 Hz below it.
    const auto hp = sysid::butterworth(n, BandType::highpass, 1000, 0, 10000);
    const double rise =
        20 * std::log10(std::abs(sysid::sos_frequency_response(hp, 100)) / std::abs(sysid::sos_frequency_response(hp, 10)));
    EXPECT_GT(rise, 20.0 * n - 0.05) << n;
    EXPECT_LT(rise, 20.0 * n + 0.3 * n) << n;
  }
}

TEST(SignalButterworth, NarrowHighOrderBandpassStaysAccurate) {
  // 2 Hz band at 50 Hz, fs 1 kHz, order 10 (20 poles within ~0.01 of the unit circle):
  // an expanded polynomial would lose most digits; sections keep them.
  const auto f = sysid::butterworth(10, BandType::bandpass, 49, 51, 1000);
  EXPECT_NEAR(std::abs(sysid::sos_frequency_response(f, 49)), 1 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(std::abs(sysid::sos_frequency_response(f, 51)), 1 / std::sqrt(2.0), 1e-9);
  for (const C& z : section_poles(f)) EXPECT_LT(std::abs(z), 1.0);
  EXPECT_LT(multiset_distance(section_poles(f), expected_poles(10, BandType::bandpass, 49, 51, 1000)), 1e-11);
}

TEST(SignalButterworth, StateSpaceFormHasSamePolesAndResponse) {
  for (const Case& c : kCases) {
    const auto f = sysid::butterworth(c.order, c.type, c.f1, c.f2, c.fs);
    const sysid::StateSpace ss = sysid::sos_to_state_space(f);
    EXPECT_DOUBLE_EQ(ss.Ts, 1.0 / c.fs);
    EXPECT_EQ(ss.inputs(), 1);
    EXPECT_EQ(ss.outputs(), 1);
    const Eigen::Index n_poles = c.type == BandType::bandpass ? 2 * c.order : c.order;
    ASSERT_EQ(ss.order(), n_poles);  // minimal: first-order sections add one state
    const Eigen::VectorXcd eig = ss.A.eigenvalues();
    std::vector<C> ev(eig.data(), eig.data() + eig.size());
    // Eigenvalues of the block-triangular A are those of 2x2 blocks: accurate to ~1e-14;
    // repeated/clustered poles are not present in these cases.
    EXPECT_LT(multiset_distance(ev, expected_poles(c.order, c.type, c.f1, c.f2, c.fs)), 1e-9);
    for (double fr : {0.0, 0.1 * c.f1, c.f1, 0.5 * (c.f1 + c.f2), 0.3 * c.fs, 0.49 * c.fs}) {
      const C z = std::polar(1.0, 2 * kPi * fr / c.fs);
      const Eigen::MatrixXcd zI_A = z * Eigen::MatrixXcd::Identity(ss.order(), ss.order()) - ss.A.cast<C>();
      const C h = (ss.C.cast<C>() * zI_A.partialPivLu().solve(ss.B.cast<C>()))(0, 0) + ss.D(0, 0);
      EXPECT_NEAR(std::abs(h - sysid::sos_frequency_response(f, fr)), 0.0, 1e-9) << fr;
    }
  }
}

TEST(SignalButterworth, PreconditionsNameTheInequality) {
  auto msg = [](auto fn) {
    try {
      fn();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no throw");
  };
  EXPECT_NE(msg([] { sysid::butterworth(0, BandType::lowpass, 10, 0, 100); }).find("order >= 1"), std::string::npos);
  EXPECT_NE(msg([] { sysid::butterworth(2, BandType::lowpass, 0, 0, 100); }).find("f1 > 0"), std::string::npos);
  EXPECT_NE(msg([] { sysid::butterworth(2, BandType::highpass, 50, 0, 100); }).find("f1 < fs/2"), std::string::npos);
  EXPECT_NE(msg([] { sysid::butterworth(2, BandType::bandpass, 20, 20, 100); }).find("f1 < f2"), std::string::npos);
  EXPECT_NE(msg([] { sysid::butterworth(2, BandType::bandpass, 20, 50, 100); }).find("f2 < fs/2"), std::string::npos);
  EXPECT_NE(msg([] { sysid::butterworth(2, BandType::lowpass, 10, 0, -1); }).find("fs"), std::string::npos);
  EXPECT_THROW(sysid::butterworth_analog_poles(0), std::invalid_argument);
  // f2 is ignored outside bandpass
  EXPECT_NO_THROW(sysid::butterworth(2, BandType::lowpass, 10, -5, 100));
}

}  // namespace

}  // namespace test_unit_signal_butterworth
