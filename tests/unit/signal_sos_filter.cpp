// Tests of signal/sos_filter.hpp: causal cascade against the expanded difference
// equation and the state-space impulse response; filtfilt against its defining
// property (response |H|^2, zero phase) and its edge handling.
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/sos_filter.hpp>

#include <sysid/core/flush_subnormals.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>
#include "random_matrices.hpp"
#include "subnormals.hpp"

namespace test_unit_signal_sos_filter {

namespace {

using sysid::BandType;
using sysid::test::kPi;

std::vector<double> convolve(const std::vector<double>& p, const std::vector<double>& q) {
  std::vector<double> r(p.size() + q.size() - 1, 0.0);
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = 0; j < q.size(); ++j) r[i + j] += p[i] * q[j];
  return r;
}

// Direct form I of the expanded B(z)/A(z): sum a_j y[n-j] = sum b_j x[n-j], a_0 = 1.
Eigen::VectorXd difference_equation(const sysid::SecondOrderSections& f, const Eigen::VectorXd& x) {
  std::vector<double> b{1.0}, a{1.0};
  for (Eigen::Index k = 0; k < f.sos.rows(); ++k) {
    b = convolve(b, {f.sos(k, 0), f.sos(k, 1), f.sos(k, 2)});
    a = convolve(a, {f.sos(k, 3), f.sos(k, 4), f.sos(k, 5)});
  }
  Eigen::VectorXd y(x.size());
  for (Eigen::Index n = 0; n < x.size(); ++n) {
    double acc = 0.0;
    for (std::size_t j = 0; j < b.size() && static_cast<Eigen::Index>(j) <= n; ++j) acc += b[j] * x(n - j);
    for (std::size_t j = 1; j < a.size() && static_cast<Eigen::Index>(j) <= n; ++j) acc -= a[j] * y(n - j);
    y(n) = acc / a[0];
  }
  return y;
}

TEST(SignalSosFilter, MatchesExpandedDifferenceEquation) {
  // Moderate orders and cutoffs, where the expanded polynomial is itself accurate
  // (coefficient sensitivity ~ 1e3 at most), so agreement to 1e-10 of the output scale
  // checks the cascade, not the reference's round-off.
  const std::vector<sysid::SecondOrderSections> filters = {
      sysid::butterworth(4, BandType::lowpass, 100, 0, 1000), sysid::butterworth(5, BandType::highpass, 50, 0, 1000),
      sysid::butterworth(3, BandType::bandpass, 80, 200, 1000), sysid::butterworth(1, BandType::lowpass, 10, 0, 1000)};
  const Eigen::MatrixXd x = sysid::test::white_noise(2000, 3, 11);
  for (const auto& f : filters) {
    const Eigen::MatrixXd y = sysid::sos_filter(f, x);
    ASSERT_EQ(y.rows(), x.rows());
    ASSERT_EQ(y.cols(), x.cols());
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      const Eigen::VectorXd ref = difference_equation(f, x.col(c));
      EXPECT_LT((y.col(c) - ref).cwiseAbs().maxCoeff(), 1e-10 * ref.cwiseAbs().maxCoeff());
    }
  }
}

TEST(SignalSosFilter, ImpulseResponseEqualsStateSpaceMarkovParameters) {
  const auto f = sysid::butterworth(5, BandType::lowpass, 100, 0, 2000);
  const sysid::StateSpace ss = sysid::sos_to_state_space(f);
  Eigen::VectorXd impulse = Eigen::VectorXd::Zero(200);
  impulse(0) = 1.0;
  const Eigen::MatrixXd h = sysid::sos_filter(f, impulse);
  EXPECT_NEAR(h(0, 0), ss.D(0, 0), 1e-15);
  Eigen::VectorXd x = ss.B.col(0);  // A^(k-1) B
  for (Eigen::Index k = 1; k < 200; ++k) {
    EXPECT_NEAR(h(k, 0), (ss.C * x)(0), 1e-13) << k;
    x = ss.A * x;
  }
}

TEST(SignalSosFilter, AFilteredSilenceReachesZeroWithoutPassingThroughSubnormals) {
  // A burst, then silence: the sections' states decay without entering the
  // subnormal range (core/flush_subnormals.hpp), in sos_filter and in both
  // passes of filtfilt; the response before the silence is the exact recursion's.
  // Where the products are rounded one by one (no fused multiply-add) a section
  // can keep circling at a few times the smallest normal number (~5e-308): zero
  // for every purpose, and without the cost of subnormals.
  if (!sysid::ScopedFlushSubnormals::supported()) GTEST_SKIP() << "no flush-to-zero mode on this target";
  const auto f = sysid::butterworth(4, BandType::lowpass, 200, 0, 2000);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(20000);
  x.head(50).setOnes();
  x.tail(50).setOnes();  // filtfilt's backward pass decays over the silence too
  const Eigen::MatrixXd causal = sysid::sos_filter(f, x);
  EXPECT_FALSE(sysid::test::has_subnormal(causal));
  EXPECT_LT(causal.col(0).segment(10000, 5000).cwiseAbs().maxCoeff(), 1e-300);
  const Eigen::VectorXd exact = difference_equation(f, x.head(400));
  EXPECT_LT((causal.col(0).head(400) - exact).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::MatrixXd zero_phase = sysid::filtfilt(f, x);
  EXPECT_FALSE(sysid::test::has_subnormal(zero_phase));
  EXPECT_LT(zero_phase.col(0).segment(5000, 10000).cwiseAbs().maxCoeff(), 1e-300);
  EXPECT_FALSE(sysid::test::flushing_subnormals());  // the caller's mode is restored
}

TEST(SignalSosFilter, ColumnsAreFilteredIndependently) {
  const auto f = sysid::butterworth(3, BandType::bandpass, 20, 60, 500);
  const Eigen::MatrixXd x = sysid::test::white_noise(500, 3, 5);
  const Eigen::MatrixXd y = sysid::sos_filter(f, x);
  const Eigen::MatrixXd z = sysid::filtfilt(f, x);
  for (Eigen::Index c = 0; c < 3; ++c) {
    EXPECT_EQ((y.col(c) - sysid::sos_filter(f, x.col(c))).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((z.col(c) - sysid::filtfilt(f, x.col(c))).cwiseAbs().maxCoeff(), 0.0);
  }
}

// filtfilt has frequency response |H(f)|^2 with zero phase. A sum of sinusoids on the
// frequency grid k fs / M is analysed over an exact window of M samples in the middle
// of the record, where the start-up transients (decaying like r^n, r = largest pole
// radius, here r^1500 < 1e-30) are gone; the DFT over the window then separates the
// sinusoids exactly, so the only error is round-off (~1e-13).
void check_zero_phase(const sysid::SecondOrderSections& f, const std::vector<int>& bins) {
  const double fs = f.fs_hz;
  const Eigen::Index M = 1000, N = 5000, start = 2000;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> amp(0.5, 2.0), ph(0.0, 2 * kPi);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(N, 2);
  std::vector<std::vector<std::complex<double>>> c_in(2);
  for (Eigen::Index col = 0; col < 2; ++col) {
    for (int k : bins) {
      const double a = amp(rng), p = ph(rng);
      c_in[col].push_back(std::polar(a, p));
      for (Eigen::Index n = 0; n < N; ++n) x(n, col) += a * std::cos(2 * kPi * k * n / static_cast<double>(M) + p);
    }
  }
  const Eigen::MatrixXd y = sysid::filtfilt(f, x);
  for (Eigen::Index col = 0; col < 2; ++col) {
    for (std::size_t i = 0; i < bins.size(); ++i) {
      const int k = bins[i];
      std::complex<double> c(0, 0);
      for (Eigen::Index n = start; n < start + M; ++n)
        c += y(n, col) * std::polar(1.0, -2 * kPi * k * n / static_cast<double>(M));
      c *= 2.0 / static_cast<double>(M);  // complex amplitude a e^{i p} of a cos(.. + p)
      const double h2 = std::norm(sysid::sos_frequency_response(f, k * fs / M));
      const std::complex<double> want = h2 * c_in[col][i];
      EXPECT_LT(std::abs(c - want), 1e-6 * std::abs(c_in[col][i])) << "bin " << k;
      if (h2 > 1e-3) {
        // amplitude ratio |H|^2 and phase shift 0
        EXPECT_NEAR(std::abs(c) / std::abs(c_in[col][i]), h2, 1e-6);
        EXPECT_NEAR(std::arg(c / c_in[col][i]), 0.0, 1e-6);
      }
    }
  }
}

TEST(SignalSosFilter, FiltfiltHasZeroPhaseAndSquaredMagnitude) {
  const std::vector<int> bins = {3, 20, 45, 50, 55, 80, 120, 200, 330, 470};
  check_zero_phase(sysid::butterworth(4, BandType::lowpass, 50, 0, 1000), bins);
  check_zero_phase(sysid::butterworth(5, BandType::lowpass, 100, 0, 1000), bins);
  check_zero_phase(sysid::butterworth(3, BandType::highpass, 60, 0, 1000), bins);
  check_zero_phase(sysid::butterworth(2, BandType::bandpass, 40, 130, 1000), bins);
}

TEST(SignalSosFilter, ConstantPassesLowpassFiltfiltUnchanged) {
  // With the steady-state initial conditions a constant is already at equilibrium in
  // every pass, so the output equals the input to round-off, edges included.
  for (int n : {1, 2, 4, 7}) {
    const auto f = sysid::butterworth(n, BandType::lowpass, 20, 0, 1000);
    const Eigen::MatrixXd x = Eigen::MatrixXd::Constant(300, 2, -3.25);
    const Eigen::MatrixXd y = sysid::filtfilt(f, x);
    EXPECT_LT((y - x).cwiseAbs().maxCoeff(), 1e-11) << n;
    // A highpass removes it entirely, edges included.
    const auto h = sysid::butterworth(n, BandType::highpass, 20, 0, 1000);
    EXPECT_LT(sysid::filtfilt(h, x).cwiseAbs().maxCoeff(), 1e-11) << n;
  }
  // Causal filtering from zero state, by contrast, shows the step response at the start.
  const auto f = sysid::butterworth(4, BandType::lowpass, 20, 0, 1000);
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(300, 1.0);
  EXPECT_GT(std::abs(sysid::sos_filter(f, c)(0, 0) - 1.0), 0.9);
}

TEST(SignalSosFilter, SmoothSignalKeepsItsEdges) {
  // A slow sinusoid on an offset, deep in the passband (1 - |H|^2 < 1e-9 at 2 Hz):
  // the odd extension continues value and slope across each edge but flips the
  // curvature, a jump of 2 |x''| <= 2 (2 pi 2 Hz)^2 = 316 /s^2; the filter's response to
  // that is of order jump * tau^2 with tau ~ 2.6 / (2 pi 100 Hz) = 4.2 ms, i.e. ~5e-3
  // (measured 2.5e-4). Zero-state filtering instead errs by the full offset (~2.2).
  const auto f = sysid::butterworth(4, BandType::lowpass, 100, 0, 1000);
  const Eigen::Index N = 400;
  Eigen::VectorXd x(N);
  for (Eigen::Index n = 0; n < N; ++n) x(n) = 3.0 + std::sin(2 * kPi * 2.0 * n / 1000.0 + 0.4);
  const Eigen::VectorXd y = sysid::filtfilt(f, x);
  EXPECT_LT((y - x).cwiseAbs().maxCoeff(), 5e-3);
  const Eigen::VectorXd naive = sysid::sos_filter(f, sysid::sos_filter(f, x).colwise().reverse().eval()).colwise().reverse();
  EXPECT_GT((naive - x).cwiseAbs().maxCoeff(), 1.0);
}

TEST(SignalSosFilter, PadlengthPrecondition) {
  // 2 second-order sections: padlen = 3 * (2*2 + 1) = 15; need more than 15 samples.
  const auto f4 = sysid::butterworth(4, BandType::lowpass, 50, 0, 1000);
  EXPECT_THROW(sysid::filtfilt(f4, Eigen::VectorXd::Ones(15)), std::invalid_argument);
  EXPECT_NO_THROW(sysid::filtfilt(f4, Eigen::VectorXd::Ones(16)));
  try {
    sysid::filtfilt(f4, Eigen::VectorXd::Ones(10));
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("samples > padlen = 15"), std::string::npos) << e.what();
  }
  // Order 5: two biquads + one first-order section; the missing z^-2 terms are not
  // counted: padlen = 3 * (2*3 + 1 - 1) = 18.
  const auto f5 = sysid::butterworth(5, BandType::lowpass, 50, 0, 1000);
  EXPECT_THROW(sysid::filtfilt(f5, Eigen::VectorXd::Ones(18)), std::invalid_argument);
  EXPECT_NO_THROW(sysid::filtfilt(f5, Eigen::VectorXd::Ones(19)));
  // Empty cascade and a pole at z = 1 are rejected.
  sysid::SecondOrderSections empty;
  empty.fs_hz = 1000;
  EXPECT_THROW(sysid::sos_filter(empty, Eigen::VectorXd::Ones(40)), std::invalid_argument);
  sysid::SecondOrderSections integrator;
  integrator.fs_hz = 1000;
  integrator.sos.resize(1, 6);
  integrator.sos << 1, 0, 0, 1, -1, 0;
  EXPECT_NO_THROW(sysid::sos_filter(integrator, Eigen::VectorXd::Ones(40)));
  EXPECT_THROW(sysid::filtfilt(integrator, Eigen::VectorXd::Ones(40)), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_signal_sos_filter
