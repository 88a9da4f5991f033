// Tests for the transfer-function helpers (include/sysid/core/transfer_function.hpp).
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/transfer_function.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>
#include "random_matrices.hpp"

namespace test_unit_core_transfer_function {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXcd;
using Eigen::VectorXd;
using Complex = std::complex<double>;
using LComplex = std::complex<long double>;
using sysid::test::kPi;
using sysid::test::match_error;

VectorXd vec(std::initializer_list<double> v) {
  VectorXd r(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double x : v) r[i++] = x;
  return r;
}

/// Horner evaluation in long double (64-bit significand on x86-64): the
/// reference "direct polynomial evaluation", ~2000x more precise than double.
LComplex horner(const VectorXd& c, LComplex x) {
  LComplex s = 0.0L;
  for (Eigen::Index i = 0; i < c.size(); ++i) s = s * x + static_cast<long double>(c[i]);
  return s;
}

Complex tf_value(const sysid::TransferFunction& tf, Complex x) {
  const LComplex v = horner(tf.num, LComplex(x.real(), x.imag())) / horner(tf.den, LComplex(x.real(), x.imag()));
  return {static_cast<double>(v.real()), static_cast<double>(v.imag())};
}

bool long_double_is_extended() { return std::numeric_limits<long double>::digits >= 64; }

/// Largest relative FRF difference between the realisation and the polynomial
/// ratio over frequencies f (Hz).
double max_rel_frf_error(const sysid::TransferFunction& tf, const VectorXd& f) {
  const sysid::StateSpace s = sysid::to_state_space(tf);
  const auto G = sysid::frequency_response(s, f);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    const double w = 2.0 * kPi * f[i];
    const Complex x = tf.Ts > 0 ? std::polar(1.0, w * tf.Ts) : Complex(0.0, w);
    const Complex ref = tf_value(tf, x);
    worst = std::max(worst, std::abs(G[i](0, 0) - ref) / std::abs(ref));
  }
  return worst;
}

/// Roots of x^2 + a x + b.
std::vector<Complex> quadratic_roots(double a, double b) {
  const Complex disc = std::sqrt(Complex(a * a - 4.0 * b, 0.0));
  return {(-a + disc) / 2.0, (-a - disc) / 2.0};
}

// ---- the Par2 model (Ts = 1/2000) -------------------------------------------
// GU(z) = -0.055 (z-1.003)(z-1.15)(z^2-1.993z+1.002)(z+1)^2(z^2-1.947z+0.985)(z^2-1.914z+0.989)
//         / [(z^2-1.985z+0.993)(z^2-1.561z+0.641)(z^2-1.947z+0.988)(z^2-1.901z+0.976)(z^2-1.586z+0.97)]
const std::vector<VectorXd>& par2_num_factors() {
  static const std::vector<VectorXd> f = {vec({1, -1.003}),        vec({1, -1.15}), vec({1, -1.993, 1.002}), vec({1, 1}),
                                          vec({1, 1}),             vec({1, -1.947, 0.985}), vec({1, -1.914, 0.989})};
  return f;
}
const std::vector<VectorXd>& par2_den_factors() {
  static const std::vector<VectorXd> f = {vec({1, -1.985, 0.993}), vec({1, -1.561, 0.641}), vec({1, -1.947, 0.988}),
                                          vec({1, -1.901, 0.976}), vec({1, -1.586, 0.97})};
  return f;
}
sysid::TransferFunction par2() {
  sysid::TransferFunction tf;
  tf.num = vec({-0.055});
  for (const VectorXd& f : par2_num_factors()) tf.num = sysid::poly_multiply(tf.num, f);
  tf.den = vec({1.0});
  for (const VectorXd& f : par2_den_factors()) tf.den = sysid::poly_multiply(tf.den, f);
  tf.Ts = 1.0 / 2000.0;
  return tf;
}
VectorXcd roots_of(const std::vector<VectorXd>& factors) {
  std::vector<Complex> r;
  for (const VectorXd& f : factors) {
    if (f.size() == 2) {
      r.emplace_back(-f[1], 0.0);
    } else {
      for (const Complex& q : quadratic_roots(f[1], f[2])) r.push_back(q);
    }
  }
  return Eigen::Map<VectorXcd>(r.data(), static_cast<Eigen::Index>(r.size()));
}

TEST(CoreTransferFunction, PolynomialHelpers) {
  VectorXcd r(2);
  r << 1.0, 2.0;
  EXPECT_EQ(sysid::poly_from_roots(r), vec({1, -3, 2}));
  VectorXcd pair(2);
  pair << Complex(1, 2), Complex(1, -2);
  EXPECT_LT((sysid::poly_from_roots(pair) - vec({1, -2, 5})).norm(), 1e-15);
  EXPECT_EQ(sysid::poly_from_roots(VectorXcd()), vec({1}));
  VectorXcd lonely(1);
  lonely << Complex(1, 2);
  EXPECT_THROW(sysid::poly_from_roots(lonely), std::invalid_argument);
  EXPECT_EQ(sysid::poly_multiply(vec({1, 2}), vec({1, -3, 4})), vec({1, -1, -2, 8}));
  EXPECT_EQ(sysid::poly_multiply(vec({2}), vec({1, 1})), vec({2, 2}));
  EXPECT_EQ(sysid::poly_multiply(VectorXd(), vec({1, 1})).size(), 0);
}

TEST(CoreTransferFunction, Par2PolesStabilityAndFrequencyResponse) {
  const sysid::TransferFunction tf = par2();
  ASSERT_EQ(tf.num.size(), 11);
  ASSERT_EQ(tf.den.size(), 11);
  const sysid::StateSpace s = sysid::to_state_space(tf);
  EXPECT_EQ(s.order(), 10);
  EXPECT_EQ(s.Ts, tf.Ts);
  // Poles = roots of the factors. Root sensitivity to the rounding of den's
  // coefficients is ~1e-13 / |den'(p)| with |den'(p)| >~ 1e-5 here: 1e-8.
  const VectorXcd p = sysid::poles(s);
  EXPECT_LT(match_error(roots_of(par2_den_factors()), p), 1e-8);
  EXPECT_LT(p.cwiseAbs().maxCoeff(), 1.0);  // stable
  // FRF of the realisation = num/den evaluated directly, to 1e-9 relative. Near
  // the 28.5 Hz resonance den(z) ~ 5e-8 while its coefficients reach ~200: plain
  // double Horner is only ~5e-7 accurate there, so the reference is long double.
  // The double zero at z = -1 makes relative error meaningless near Nyquist.
  if (!long_double_is_extended()) GTEST_SKIP() << "long double is not extended precision here";
  EXPECT_LT(max_rel_frf_error(tf, VectorXd::LinSpaced(4001, 0.0, 950.0)), 1e-9);
  // and densely around the lightly damped modes and the zero pair at 30 Hz
  EXPECT_LT(max_rel_frf_error(tf, VectorXd::LinSpaced(2001, 25.0, 35.0)), 1e-9);
}

TEST(CoreTransferFunction, Par2ZeroPoleGainAndFactoredForm) {
  const sysid::StateSpace s = sysid::to_state_space(par2());
  const sysid::ZeroPoleGain zpk = sysid::zero_pole_gain(s);
  EXPECT_EQ(zpk.Ts, 1.0 / 2000.0);
  EXPECT_NEAR(zpk.gain, -0.055, 1e-12);
  ASSERT_EQ(zpk.zeros.size(), 10);
  ASSERT_EQ(zpk.poles.size(), 10);
  // The double zero at -1 splits by ~sqrt(eps * cond) ~ 1e-7; simple zeros are
  // accurate to ~1e-9.
  EXPECT_LT(match_error(roots_of(par2_num_factors()), zpk.zeros), 1e-6);
  // Parse-free check of the factors: every quadratic's (a, b) recovered from a
  // computed conjugate pair agrees with the model to 1e-6.
  for (const auto* factors : {&par2_num_factors(), &par2_den_factors()}) {
    const VectorXcd& roots = factors == &par2_num_factors() ? zpk.zeros : zpk.poles;
    for (const VectorXd& f : *factors) {
      if (f.size() != 3) continue;
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index i = 0; i < roots.size(); ++i) {
        if (roots[i].imag() <= 0.0) continue;
        best = std::min(best, std::hypot(-2.0 * roots[i].real() - f[1], std::norm(roots[i]) - f[2]));
      }
      EXPECT_LT(best, 1e-6) << "factor z^2 + " << f[1] << " z + " << f[2];
    }
  }
  const std::string text = sysid::format_factored(zpk);
  EXPECT_EQ(text.rfind("-0.055 (", 0), 0u) << text;
  for (const char* factor : {"(z-1.003)", "(z-1.15)", "(z^2-1.993z+1.002)", "(z+1)^2", "(z^2-1.947z+0.985)",
                             "(z^2-1.914z+0.989)", "(z^2-1.985z+0.993)", "(z^2-1.561z+0.641)", "(z^2-1.947z+0.988)",
                             "(z^2-1.901z+0.976)", "(z^2-1.586z+0.97)"})
    EXPECT_NE(text.find(factor), std::string::npos) << factor << " missing in " << text;
  const std::size_t slash = text.find(" / [");
  ASSERT_NE(slash, std::string::npos);
  EXPECT_GT(text.find("(z^2-1.985z+0.993)"), slash);  // a denominator factor after the bar
  EXPECT_LT(text.find("(z+1)^2"), slash);
  EXPECT_EQ(text.back(), ']');
}

TEST(CoreTransferFunction, ClusteredPolesNearOneOrderTen) {
  // Five lightly damped pairs (zeta 0.01 .. 0.02) within 0.25 of z = 1, and a
  // numerator with a double zero at Nyquist and two more lightly damped pairs.
  // Every factor coefficient is a multiple of 2^-8 (x^2 - (2 - k/256) x + (1 - j/256)),
  // so poly_multiply is exact (integers < 769^5 < 2^53 after scaling by 256^5)
  // and the factored form is an exact, well-conditioned reference that needs no
  // extended precision: each factor evaluates to ~1e-12 relative even at its
  // resonance. The coefficients themselves reach ~240 while den on the unit
  // circle drops to ~3e-11: measured, a plain (unshifted) companion form is only
  // ~6e-4 accurate here, the shifted realisation ~3e-13.
  struct Quad {
    int k, j;
  };
  const std::vector<Quad> den_q = {{3, 1}, {5, 2}, {8, 2}, {12, 3}, {20, 4}};
  const std::vector<Quad> num_q = {{6, 2}, {10, 3}};
  auto quad = [](Quad q) { return vec({1.0, -(2.0 - q.k / 256.0), 1.0 - q.j / 256.0}); };
  sysid::TransferFunction tf;
  tf.Ts = 1.0 / 2000.0;
  tf.den = vec({1.0});
  for (const Quad& q : den_q) tf.den = sysid::poly_multiply(tf.den, quad(q));
  tf.num = vec({1.0 / 1024.0});
  for (const VectorXd& f : {vec({1, 1}), vec({1, 1}), vec({1, -0.5})}) tf.num = sysid::poly_multiply(tf.num, f);
  for (const Quad& q : num_q) tf.num = sysid::poly_multiply(tf.num, quad(q));
  const sysid::StateSpace s = sysid::to_state_space(tf);
  // poles: the roots of the quadratics (simple, separated by >= 0.02: accurate
  // to ~1e-10 in a balanced eigensolver)
  std::vector<Complex> expected;
  for (const Quad& q : den_q) {
    const VectorXd c = quad(q);
    for (const Complex& r : quadratic_roots(c[1], c[2])) expected.push_back(r);
  }
  EXPECT_LT(match_error(Eigen::Map<VectorXcd>(expected.data(), 10), sysid::poles(s)), 1e-9);
  // frequency grid up to 0.95 Nyquist plus the pole angles themselves
  VectorXd f(1000 + 5);
  f.head(1000) = VectorXd::LinSpaced(1000, 0.0, 950.0);
  for (int i = 0; i < 5; ++i) f[1000 + i] = std::arg(expected[2 * i]) / (2 * kPi * tf.Ts);
  const auto G = sysid::frequency_response(s, f);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    const Complex z = std::polar(1.0, 2 * kPi * f[i] * tf.Ts);
    Complex ref = (z + 1.0) * (z + 1.0) * (z - 0.5) / 1024.0;
    for (const Quad& q : num_q) ref *= z * z - (2.0 - q.k / 256.0) * z + (1.0 - q.j / 256.0);
    for (const Quad& q : den_q) ref /= z * z - (2.0 - q.k / 256.0) * z + (1.0 - q.j / 256.0);
    worst = std::max(worst, std::abs(G[i](0, 0) - ref) / std::abs(ref));
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(CoreTransferFunction, RandomTransferFunctionsSweep) {
  // Orders 0..10, all relative degrees, discrete and continuous, random coefficients
  // with stable, well separated roots: the realisation matches num/den to 1e-10.
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> rad(0.2, 0.9), ang(0.1, 3.0), gain(-2.0, 2.0);
  for (double Ts : {0.0, 0.01}) {
    for (Eigen::Index n = 0; n <= 10; ++n)
      for (Eigen::Index q = 0; q <= n; ++q) {
        auto random_roots = [&](Eigen::Index count) {
          std::vector<Complex> r;
          while (static_cast<Eigen::Index>(r.size()) + 1 < count) {
            const Complex c = std::polar(rad(rng), ang(rng));
            const Complex root = Ts > 0 ? c : Complex(-10.0 * (1.0 - c.real()), 10.0 * c.imag());  // continuous: LHP
            r.push_back(root);
            r.push_back(std::conj(root));
          }
          if (static_cast<Eigen::Index>(r.size()) < count) r.emplace_back(Ts > 0 ? rad(rng) - 0.5 : -10.0 * rad(rng), 0.0);
          return VectorXcd(Eigen::Map<VectorXcd>(r.data(), count));
        };
        sysid::TransferFunction tf;
        tf.den = 1.7 * sysid::poly_from_roots(random_roots(n));  // non-monic on purpose
        tf.num = gain(rng) * sysid::poly_from_roots(random_roots(q));
        tf.Ts = Ts;
        const VectorXd f = VectorXd::LinSpaced(50, 0.0, Ts > 0 ? 49.0 : 5.0);
        EXPECT_LT(max_rel_frf_error(tf, f), 1e-10) << "Ts=" << Ts << " n=" << n << " q=" << q;
        // zero_pole_gain: gain = ratio of leading coefficients
        const sysid::ZeroPoleGain zpk = sysid::zero_pole_gain(sysid::to_state_space(tf));
        EXPECT_NEAR(zpk.gain / (tf.num[0] / tf.den[0]), 1.0, 1e-9) << "n=" << n << " q=" << q;
        EXPECT_EQ(zpk.zeros.size(), q);
      }
  }
}

TEST(CoreTransferFunction, ZeroPoleGainReproducesChannelOfMimoModel) {
  // G(x) = gain prod(x - z) / prod(x - p) must hold for every channel, including
  // non-minimal ones whose unseen modes appear as cancelling zero/pole pairs.
  std::mt19937_64 rng(13);
  std::normal_distribution<double> g;
  auto randn = [&](Eigen::Index r, Eigen::Index c) {
    MatrixXd m(r, c);
    for (Eigen::Index j = 0; j < c; ++j)
      for (Eigen::Index i = 0; i < r; ++i) m(i, j) = g(rng);
    return m;
  };
  std::vector<sysid::StateSpace> models;
  for (Eigen::Index n : {1, 4, 9}) {
    MatrixXd A = randn(n, n);
    A *= 0.9 / A.eigenvalues().cwiseAbs().maxCoeff();
    models.emplace_back(A, randn(n, 2), randn(3, n), randn(3, 2), 0.01);
    models.emplace_back(A, randn(n, 2), randn(3, n), MatrixXd::Zero(3, 2), 0.01);
  }
  // non-minimal: diag(-1..-4), G11 = 1/(s+1) but the realisation has 4 states
  const MatrixXd A4 = VectorXd::LinSpaced(4, -1.0, -4.0).asDiagonal();
  models.emplace_back(A4, (MatrixXd(4, 2) << 1, 0, 0, 1, 1, 0, 0, 1).finished(),
                      (MatrixXd(2, 4) << 1, 1, 0, 0, 0, 0, 1, 2).finished(), MatrixXd::Zero(2, 2), 0.0);
  for (const sysid::StateSpace& s : models)
    for (Eigen::Index i = 0; i < s.outputs(); ++i)
      for (Eigen::Index j = 0; j < s.inputs(); ++j) {
        const sysid::ZeroPoleGain zpk = sysid::zero_pole_gain(s, i, j);
        for (const Complex x : {Complex(0.3, 0.7), Complex(-1.3, 0.2), Complex(2.0, -0.5)}) {
          Complex v = zpk.gain;
          for (Eigen::Index k = 0; k < zpk.zeros.size(); ++k) v *= x - zpk.zeros[k];
          for (Eigen::Index k = 0; k < zpk.poles.size(); ++k) v /= x - zpk.poles[k];
          const Complex ref = sysid::frequency_response_at(s, x)(i, j);
          EXPECT_LT(std::abs(v - ref), 1e-9 * std::max(1e-3, std::abs(ref))) << "n=" << s.order() << " (" << i << "," << j << ") x=" << x;
        }
      }
  const sysid::ZeroPoleGain g11 = sysid::zero_pole_gain(models.back(), 0, 0);
  VectorXcd unseen(3);
  unseen << -2.0, -3.0, -4.0;
  EXPECT_LT(match_error(unseen, g11.zeros), 1e-12);
  EXPECT_NEAR(g11.gain, 1.0, 1e-12);
}

TEST(CoreTransferFunction, ZeroChannel) {
  const sysid::StateSpace s(MatrixXd::Identity(2, 2) * 0.5, (MatrixXd(2, 1) << 1, 0).finished(),
                            (MatrixXd(1, 2) << 0, 1).finished(), MatrixXd::Zero(1, 1), 0.1);
  const sysid::ZeroPoleGain zpk = sysid::zero_pole_gain(s);
  EXPECT_EQ(zpk.gain, 0.0);
  EXPECT_EQ(zpk.zeros.size(), 0);
  EXPECT_EQ(zpk.poles.size(), 2);
  EXPECT_EQ(sysid::format_factored(zpk), "0 / [(z-0.5)^2]");
}

TEST(CoreTransferFunction, FormatFactoredConventions) {
  sysid::ZeroPoleGain zpk;
  zpk.gain = 3.0;
  zpk.Ts = 0.0;
  zpk.zeros.resize(3);
  zpk.zeros << 0.0, 0.0, -0.5;
  zpk.poles.resize(4);
  zpk.poles << Complex(-1, 2), Complex(-1, -2), -1.0, -1.0 + 1e-12;
  EXPECT_EQ(sysid::format_factored(zpk), "3 s^2(s+0.5) / [(s+1)^2(s^2+2s+5)]");
  zpk.Ts = 0.1;
  zpk.zeros.resize(0);
  zpk.poles.resize(2);
  zpk.poles << Complex(0.5, 0.5), Complex(0.5, -0.5);
  zpk.gain = -0.0123456;
  EXPECT_EQ(sysid::format_factored(zpk), "-0.01235 / [(z^2-z+0.5)]");
  EXPECT_EQ(sysid::format_factored(zpk, 2), "-0.012 / [(z^2-z+0.5)]");
  zpk.poles.resize(0);
  EXPECT_EQ(sysid::format_factored(zpk), "-0.01235");
}

TEST(CoreTransferFunction, ToStateSpacePreconditionsAndLeadingZeros) {
  sysid::TransferFunction bad{vec({1, 2, 3}), vec({1, 2}), 0.1};
  EXPECT_THROW(sysid::to_state_space(bad), std::invalid_argument);
  sysid::TransferFunction zero_den{vec({1}), vec({0, 0}), 0.1};
  EXPECT_THROW(sysid::to_state_space(zero_den), std::invalid_argument);
  sysid::TransferFunction nan{vec({1}), vec({1, std::nan("")}), 0.1};
  EXPECT_THROW(sysid::to_state_space(nan), std::invalid_argument);
  // leading zeros are ignored: (2z + 1) / (z - 0.5) with padding
  const sysid::TransferFunction padded{vec({0, 0, 2, 1}), vec({0, 1, -0.5}), 0.1};
  const sysid::StateSpace s = sysid::to_state_space(padded);
  EXPECT_EQ(s.order(), 1);
  const Complex x(0.3, 0.4);
  EXPECT_LT(std::abs(sysid::frequency_response_at(s, x)(0, 0) - (2.0 * x + 1.0) / (x - 0.5)), 1e-14);
  // static gain
  const sysid::StateSpace g = sysid::to_state_space({vec({3}), vec({2}), 0.0});
  EXPECT_EQ(g.order(), 0);
  EXPECT_EQ(g.D(0, 0), 1.5);
}

}  // namespace

}  // namespace test_unit_core_transfer_function
