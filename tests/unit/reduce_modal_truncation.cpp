// Tests for sysid::modal_truncation (include/sysid/reduce/modal_truncation.hpp).
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/reduce/modal_truncation.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include "random_matrices.hpp"

namespace test_unit_reduce_modal_truncation {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using sysid::test::kPi;

/// Observer canonical form of N(q)/A(q) (A monic, degree n; N of degree < n, strictly
/// proper): the state-space form a polynomial (AR/ARX) model is converted to.
sysid::StateSpace companion(const VectorXd& a, const VectorXd& num, double Ts) {
  const int n = static_cast<int>(a.size()) - 1;
  MatrixXd A = MatrixXd::Zero(n, n), B(n, 1), C = MatrixXd::Zero(1, n);
  for (int i = 0; i < n; ++i) {
    A(i, 0) = -a(i + 1);
    if (i + 1 < n) A(i, i + 1) = 1.0;
    B(i, 0) = num(i);
  }
  C(0, 0) = 1.0;
  return sysid::StateSpace(A, B, C, MatrixXd::Zero(1, 1), Ts);
}

/// Monic polynomial (descending powers of z) with the given poles (conjugates added).
VectorXd poly_from_pairs(const std::vector<std::complex<double>>& pairs) {
  Eigen::VectorXcd c = Eigen::VectorXcd::Ones(1);
  for (std::complex<double> p : pairs)
    for (std::complex<double> r : {p, std::conj(p)}) {
      Eigen::VectorXcd next = Eigen::VectorXcd::Zero(c.size() + 1);
      next.head(c.size()) = c;
      next.tail(c.size()) -= r * c;
      c = next;
    }
  return c.real();
}

struct ArModel {
  sysid::StateSpace sys;
  std::vector<double> f_hz, zeta;
};

/// AR(16)-like model (8 resonances at fs = 1 kHz), two of them (60 and 95 Hz) in the
/// band [50, 120] Hz, the others at 8, 30, 160, 240, 330, 420 Hz.
ArModel ar16() {
  const double Ts = 1e-3;
  ArModel m;
  m.f_hz = {8.0, 30.0, 60.0, 95.0, 160.0, 240.0, 330.0, 420.0};
  m.zeta = {0.2, 0.1, 0.02, 0.03, 0.05, 0.1, 0.08, 0.15};
  std::vector<std::complex<double>> pairs;
  for (std::size_t i = 0; i < m.f_hz.size(); ++i) {
    const double w = 2 * kPi * m.f_hz[i], z = m.zeta[i];
    pairs.push_back(std::exp(std::complex<double>(-z * w, w * std::sqrt(1 - z * z)) * Ts));
  }
  VectorXd num(16);
  for (int i = 0; i < 16; ++i) num(i) = std::cos(0.7 * i) / (1.0 + i);
  m.sys = companion(poly_from_pairs(pairs), num, Ts);
  return m;
}

TEST(ReduceModalTruncation, Ar16KeepsTheTwoInBandModesExactly) {
  const ArModel ar = ar16();
  sysid::ModalTruncationOptions o;
  o.f_lo_hz = 50.0;
  o.f_hi_hz = 120.0;
  const sysid::ReductionResult res = sysid::modal_truncation(ar.sys, o);
  ASSERT_EQ(res.order, 4);
  ASSERT_EQ(res.kept_modes.size(), 2u);
  EXPECT_EQ(res.removed_modes.size(), 6u);
  // The reduced poles are poles of the full model (same eigenvalue computation), and
  // their frequencies are the designed ones up to the polynomial's root conditioning.
  const std::vector<sysid::Mode> full = sysid::modal_table(ar.sys), red = sysid::modal_table(res.model);
  ASSERT_EQ(red.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const sysid::Mode& mf = full[static_cast<std::size_t>(k + 2)];
    EXPECT_NEAR(red[static_cast<std::size_t>(k)].freq_hz / mf.freq_hz, 1.0, 1e-12);
    EXPECT_NEAR(red[static_cast<std::size_t>(k)].damping / mf.damping, 1.0, 1e-10);
    // Roots of a degree-16 polynomial whose coefficients carry rounding: ~1e-10 here.
    EXPECT_NEAR(red[static_cast<std::size_t>(k)].freq_hz / ar.f_hz[static_cast<std::size_t>(k + 2)], 1.0, 1e-7);
    EXPECT_NEAR(res.kept_modes[static_cast<std::size_t>(k)].freq_hz, red[static_cast<std::size_t>(k)].freq_hz, 1e-9);
  }
  // The reported error is the same figure reduction_error() gives for the two models
  // (different grids: within their resolution).
  const sysid::HinfErrorEstimate e = sysid::reduction_error(ar.sys, res.model);
  EXPECT_NEAR(res.hinf_error / e.value, 1.0, 0.01);
}

TEST(ReduceModalTruncation, KeepDcGainWhenAsked) {
  const ArModel ar = ar16();
  sysid::ModalTruncationOptions o;
  o.f_lo_hz = 50.0;
  o.f_hi_hz = 120.0;
  const VectorXd f0 = VectorXd::Zero(1);
  const std::complex<double> g0 = sysid::frequency_response(ar.sys, f0)[0](0, 0);
  const sysid::ReductionResult plain = sysid::modal_truncation(ar.sys, o);
  o.keep_dc_gain = true;
  const sysid::ReductionResult dc = sysid::modal_truncation(ar.sys, o);
  EXPECT_EQ(dc.order, 4);
  const std::complex<double> gdc = sysid::frequency_response(dc.model, f0)[0](0, 0);
  const std::complex<double> gplain = sysid::frequency_response(plain.model, f0)[0](0, 0);
  // Exact up to the rounding of the modal basis (kappa ~ 1e3 here).
  EXPECT_LT(std::abs(gdc - g0), 1e-9 * std::abs(g0));
  EXPECT_LT(dc.dc_error, 1e-9 * std::abs(g0));
  EXPECT_GT(std::abs(gplain - g0), 1e-3 * std::abs(g0));  // the option matters here
  // Poles are unchanged by the D correction.
  const auto a = sysid::modal_table(plain.model), b = sysid::modal_table(dc.model);
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k].pole, b[k].pole);
}

TEST(ReduceModalTruncation, DominantModesByPeakGain) {
  // Continuous MIMO modal system rotated by a similarity; the mode at 10 Hz has a
  // far larger peak (light damping, large residue) than the others.
  std::mt19937_64 rng(4);
  std::normal_distribution<double> g;
  const double fz[4][2] = {{10.0, 0.005}, {30.0, 0.05}, {70.0, 0.2}, {120.0, 0.3}};
  MatrixXd A = MatrixXd::Zero(9, 9), B(9, 2), C(2, 9);
  for (int k = 0; k < 4; ++k) {
    const double w = 2 * kPi * fz[k][0], z = fz[k][1];
    A.block(2 * k, 2 * k, 2, 2) << -z * w, w * std::sqrt(1 - z * z), -w * std::sqrt(1 - z * z), -z * w;
  }
  A(8, 8) = -2.0;
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 2; ++j) {
      B(i, j) = g(rng);
      C(j, i) = g(rng);
    }
  MatrixXd T(9, 9);
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 9; ++j) T(i, j) = g(rng) + (i == j ? 3.0 : 0.0);
  const sysid::StateSpace s(T * A * T.inverse(), T * B, C * T.inverse(), MatrixXd::Zero(2, 2), 0.0);
  sysid::ModalTruncationOptions o;
  o.order = 3;  // the 10 Hz pair, then the one remaining slot takes the real pole
  const sysid::ReductionResult res = sysid::modal_truncation(s, o);
  EXPECT_EQ(res.order, 3);
  ASSERT_EQ(res.kept_modes.size(), 2u);
  EXPECT_NEAR(res.kept_modes[1].freq_hz, 10.0, 1e-9);
  EXPECT_FALSE(res.kept_modes[0].complex_pair);
  // Error is the removed modes' response: measured and finite.
  EXPECT_TRUE(std::isfinite(res.hinf_error));
  EXPECT_GT(res.hinf_error, 0.0);
}

TEST(ReduceModalTruncation, DefectiveMatrixAndBadBandThrow) {
  MatrixXd A(2, 2);
  A << 0.5, 1.0, 0.0, 0.5;  // Jordan block
  const sysid::StateSpace s(A, MatrixXd::Ones(2, 1), MatrixXd::Ones(1, 2), MatrixXd::Zero(1, 1), 1.0);
  sysid::ModalTruncationOptions o;
  EXPECT_THROW(sysid::modal_truncation(s, o), sysid::NumericalError);
  o.f_lo_hz = 10;
  o.f_hi_hz = 5;
  EXPECT_THROW(sysid::modal_truncation(s, o), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_reduce_modal_truncation
