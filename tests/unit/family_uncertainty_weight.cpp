// Tests for sysid::fit_uncertainty_weight (include/sysid/family/uncertainty_weight.hpp).
#include <sysid/core/frequency_response.hpp>
#include <sysid/family/uncertainty_weight.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>
#include "checks.hpp"
#include "random_matrices.hpp"

namespace test_unit_family_uncertainty_weight {

namespace {

using Complex = std::complex<double>;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using sysid::test::kPi;

/// A root of the discrete filter from a resonance: exp(s Ts), s = w (-zeta + j sqrt(1 - zeta^2)).
Complex root(double f_hz, double zeta, double Ts) {
  const double w = 2 * kPi * f_hz;
  return std::exp(Complex(-zeta * w, w * std::sqrt(1 - zeta * zeta)) * Ts);
}

/// |k prod (z - zeros) / prod (z - poles)| at z = exp(j 2 pi f Ts), conjugates added.
VectorXd magnitude(const VectorXd& f_hz, double Ts, double k, const std::vector<Complex>& zero_pairs,
                   const std::vector<Complex>& pole_pairs) {
  VectorXd m(f_hz.size());
  for (Eigen::Index i = 0; i < f_hz.size(); ++i) {
    const Complex z = std::polar(1.0, 2 * kPi * f_hz(i) * Ts);
    Complex h = k;
    for (Complex q : zero_pairs) h *= (z - q) * (z - std::conj(q));
    for (Complex p : pole_pairs) h /= (z - p) * (z - std::conj(p));
    m(i) = std::abs(h);
  }
  return m;
}

/// Sorted union of a log-spaced grid and linear clusters around `centres`.
VectorXd grid(double lo, double hi, int n_log, const std::vector<double>& centres, double half_width, int n_each) {
  std::vector<double> f;
  for (int i = 0; i < n_log; ++i) f.push_back(lo * std::pow(hi / lo, i / (n_log - 1.0)));
  for (double c : centres)
    for (int i = 0; i < n_each; ++i) f.push_back(c - half_width + 2 * half_width * i / (n_each - 1.0));
  std::sort(f.begin(), f.end());
  f.erase(std::unique(f.begin(), f.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }), f.end());
  return Eigen::Map<VectorXd>(f.data(), static_cast<Eigen::Index>(f.size()));
}

/// Checks every claim of the result independently of the fit: SISO at Ts, poles and
/// zeros (eigenvalues of A and of A - B D^-1 C) strictly inside the unit circle, |W|
/// evaluated afresh on the model covering the bound, the reported magnitude and
/// conservatism consistent with it.
void check_weight(const sysid::UncertaintyWeightResult& r, const VectorXd& f, const VectorXd& bound, double Ts,
                  int order) {
  const sysid::StateSpace& w = r.weight;
  ASSERT_EQ(w.inputs(), 1);
  ASSERT_EQ(w.outputs(), 1);
  ASSERT_EQ(w.order(), order);
  EXPECT_EQ(w.Ts, Ts);
  ASSERT_NE(w.D(0, 0), 0.0);
  const Eigen::VectorXcd poles = Eigen::EigenSolver<MatrixXd>(w.A, false).eigenvalues();
  const MatrixXd Az = w.A - w.B * w.C / w.D(0, 0);
  const Eigen::VectorXcd zeros = Eigen::EigenSolver<MatrixXd>(Az, false).eigenvalues();
  for (Complex p : poles) EXPECT_LT(std::abs(p), 1.0) << "pole " << p;
  for (Complex z : zeros) EXPECT_LT(std::abs(z), 1.0) << "zero " << z;

  const std::vector<Eigen::MatrixXcd> G = sysid::frequency_response(w, f);
  std::vector<double> ratios;
  double min_ratio = std::numeric_limits<double>::infinity();
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    const double m = std::abs(G[static_cast<std::size_t>(k)](0, 0));
    EXPECT_NEAR(r.magnitude(k), m, 1e-10 * m);
    if (bound(k) > 0) {
      EXPECT_GE(m, bound(k) * (1 - 1e-12)) << "at " << f(k) << " Hz";
      ratios.push_back(m / bound(k));
      min_ratio = std::min(min_ratio, m / bound(k));
    }
  }
  EXPECT_GE(r.min_ratio, 1.0);
  EXPECT_NEAR(r.min_ratio, min_ratio, 1e-10);
  std::sort(ratios.begin(), ratios.end());
  EXPECT_NEAR(r.max_conservatism, ratios.back(), 1e-9 * ratios.back());
  EXPECT_GE(r.median_conservatism, ratios.front());
  EXPECT_LE(r.median_conservatism, ratios.back());
}

struct Timed {
  sysid::UncertaintyWeightResult result;
  double seconds = 0;
};

Timed timed_fit(const VectorXd& f, const VectorXd& bound, double Ts, const sysid::UncertaintyWeightOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  Timed t{sysid::fit_uncertainty_weight(f, bound, Ts, o)};
  t.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("  %s; median %.6f, max %.6f; %.3f s\n", t.result.brief_report().c_str(), t.result.median_conservatism,
              t.result.max_conservatism, t.seconds);
  return t;
}

}  // namespace

// A bound that is the gain of a stable minimum-phase filter of the fitted order:
// the fit recovers it, so the weight follows the bound within a few percent.
TEST(FamilyUncertaintyWeight, RecoversSecondOrderFilter) {
  const double Ts = 1e-3;
  const VectorXd f = grid(1.0, 450.0, 300, {40.0, 120.0}, 8.0, 50);
  // A resonance at 40 Hz (zeta 0.03) over a damped zero pair at 120 Hz.
  const VectorXd bound = magnitude(f, Ts, 0.2, {root(120.0, 0.3, Ts)}, {root(40.0, 0.03, Ts)});
  sysid::UncertaintyWeightOptions o;
  o.order = 2;
  const Timed t = timed_fit(f, bound, Ts, o);
  check_weight(t.result, f, bound, Ts, 2);
  EXPECT_LE(t.result.median_conservatism, 1.02);
  EXPECT_LE(t.result.max_conservatism, 1.1);
}

TEST(FamilyUncertaintyWeight, RecoversFourthOrderFilter) {
  const double Ts = 1e-3;
  const VectorXd f = grid(0.5, 450.0, 300, {25.0, 60.0}, 5.0, 50);
  // Resonance 25 Hz (zeta 0.02), anti-resonance 60 Hz (zeta 0.01), a damped pole
  // pair at 200 Hz and zero pair at 5 Hz: peaks and a notch over three decades.
  const VectorXd bound = magnitude(f, Ts, 0.5, {root(60.0, 0.01, Ts), root(5.0, 0.5, Ts)},
                                   {root(25.0, 0.02, Ts), root(200.0, 0.4, Ts)});
  const double spread = bound.maxCoeff() / bound.minCoeff();
  ASSERT_GT(spread, 100.0);  // the bound spans decades: a test of the starts, not of the gain
  sysid::UncertaintyWeightOptions o;
  o.order = 4;
  const Timed t = timed_fit(f, bound, Ts, o);
  check_weight(t.result, f, bound, Ts, 4);
  EXPECT_LE(t.result.median_conservatism, 1.1);
  EXPECT_LE(t.result.max_conservatism, 1.05);  // the filter itself is in the model set
}

// The bound a family of lightly damped plants gives: the relative deviation floor
// rising from 0.05 to 0.3 over the band, with narrow peaks where the members'
// resonances move (5 at 28 Hz, 2 at 65 Hz).
VectorXd family_like_bound(const VectorXd& f) {
  VectorXd b(f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    const double x = f(k) / 100.0;
    const double floor = 0.05 + 0.25 * x * x;
    const double p1 = 5.0 / std::sqrt(1 + std::pow((f(k) - 28.0) / 0.6, 2));
    const double p2 = 2.0 / std::sqrt(1 + std::pow((f(k) - 65.0) / 1.0, 2));
    b(k) = std::max(floor, std::max(p1, p2));
  }
  return b;
}

TEST(FamilyUncertaintyWeight, CoversFamilyBoundWithOrderFourAndSix) {
  const double Ts = 5e-4;
  const VectorXd f = grid(0.5, 100.0, 250, {28.0, 65.0}, 4.0, 40);
  ASSERT_GE(f.size(), 300);
  const VectorXd bound = family_like_bound(f);
  double previous_median = std::numeric_limits<double>::infinity();
  for (int order : {4, 6}) {
    sysid::UncertaintyWeightOptions o;
    o.order = order;
    const Timed t = timed_fit(f, bound, Ts, o);
    SCOPED_TRACE(order);
    check_weight(t.result, f, bound, Ts, order);
    EXPECT_LE(t.result.median_conservatism, 2.0);
    // The peaks are followed, not covered by raising the whole weight.
    EXPECT_LE(t.result.max_conservatism, 5.0);
    // More freedom does not make the weight worse (up to the fit's tolerance).
    EXPECT_LE(t.result.median_conservatism, previous_median * 1.05);
    previous_median = t.result.median_conservatism;
  }
}

// A grid larger than the SQP's all-points limit (600): the refinement works on a
// growing working set of points; the cover must still hold at every one.
TEST(FamilyUncertaintyWeight, CoversOnLargeGrid) {
  const double Ts = 5e-4;
  const VectorXd f = grid(0.5, 100.0, 1000, {28.0, 65.0}, 4.0, 100);
  ASSERT_GT(f.size(), 1000);
  const VectorXd bound = family_like_bound(f);
  sysid::UncertaintyWeightOptions o;
  o.order = 4;
  const Timed t = timed_fit(f, bound, Ts, o);
  check_weight(t.result, f, bound, Ts, 4);
  EXPECT_LE(t.result.median_conservatism, 2.0);
}

// Points with bound 0 carry no requirement and stay out of the ratios.
TEST(FamilyUncertaintyWeight, IgnoresZeroBounds) {
  const double Ts = 5e-4;
  const VectorXd f = grid(0.5, 100.0, 250, {28.0, 65.0}, 4.0, 40);
  VectorXd bound = family_like_bound(f);
  for (Eigen::Index k = 0; k < f.size(); k += 7) bound(k) = 0.0;
  sysid::UncertaintyWeightOptions o;
  o.order = 4;
  const Timed t = timed_fit(f, bound, Ts, o);
  check_weight(t.result, f, bound, Ts, 4);
  EXPECT_TRUE(std::isfinite(t.result.max_conservatism));
  EXPECT_TRUE(sysid::test::has_warning(t.result.warnings, "bound 0"));
}

TEST(FamilyUncertaintyWeight, RejectsBadInput) {
  const double Ts = 1e-3;
  const VectorXd f = VectorXd::LinSpaced(300, 1.0, 400.0);
  const VectorXd b = VectorXd::Constant(300, 0.1);
  auto fit = [&](const VectorXd& ff, const VectorXd& bb, double ts, int order) {
    sysid::UncertaintyWeightOptions o;
    o.order = order;
    return sysid::fit_uncertainty_weight(ff, bb, ts, o);
  };
  VectorXd nan_b = b, neg_b = b, inf_b = b, nyq_f = f, nan_f = f, dec_f = f;
  nan_b(10) = std::numeric_limits<double>::quiet_NaN();
  inf_b(20) = std::numeric_limits<double>::infinity();
  neg_b(30) = -0.01;
  nyq_f(299) = 500.0;  // = Nyquist
  nan_f(5) = std::numeric_limits<double>::quiet_NaN();
  dec_f(50) = dec_f(49);
  EXPECT_THROW(fit(f, nan_b, Ts, 2), std::invalid_argument);
  EXPECT_THROW(fit(f, inf_b, Ts, 2), std::invalid_argument);
  EXPECT_THROW(fit(f, neg_b, Ts, 2), std::invalid_argument);
  EXPECT_THROW(fit(nyq_f, b, Ts, 2), std::invalid_argument);
  EXPECT_THROW(fit(nan_f, b, Ts, 2), std::invalid_argument);
  EXPECT_THROW(fit(dec_f, b, Ts, 2), std::invalid_argument);
  EXPECT_THROW(fit(-f, b, Ts, 2), std::invalid_argument);
  EXPECT_THROW(fit(f, b, Ts, 0), std::invalid_argument);
  EXPECT_THROW(fit(f, b, Ts, 7), std::invalid_argument);
  EXPECT_THROW(fit(f, b.head(299), Ts, 2), std::invalid_argument);
  EXPECT_THROW(fit(f, VectorXd::Zero(300), Ts, 2), std::invalid_argument);
  EXPECT_THROW(fit(f, b, 0.0, 2), std::invalid_argument);
  EXPECT_THROW(fit(f, b, std::numeric_limits<double>::quiet_NaN(), 2), std::invalid_argument);
  // The message names the violated inequality.
  try {
    fit(nyq_f, b, Ts, 2);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("Nyquist"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(fit(f, b, Ts, 1));
}

// A constant bound: the first-order weight's zero and pole coincide, |W| ~ constant.
TEST(FamilyUncertaintyWeight, ConstantBoundGivesFlatFirstOrderWeight) {
  const double Ts = 1e-3;
  VectorXd f(301);
  f(0) = 0.0;  // DC is allowed
  f.tail(300) = VectorXd::LinSpaced(300, 0.5, 499.0);
  const VectorXd bound = VectorXd::Constant(f.size(), 0.2);
  sysid::UncertaintyWeightOptions o;
  o.order = 1;
  const Timed t = timed_fit(f, bound, Ts, o);
  check_weight(t.result, f, bound, Ts, 1);
  EXPECT_LE(t.result.median_conservatism, 1.01);
  EXPECT_LE(t.result.max_conservatism, 1.02);
  EXPECT_TRUE(t.result.warnings.empty());
}

}  // namespace test_unit_family_uncertainty_weight
