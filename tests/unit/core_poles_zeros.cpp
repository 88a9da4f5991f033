// Tests for sysid::poles / transmission_zeros / channel_zeros
// (include/sysid/core/poles_zeros.hpp).
#include <sysid/core/errors.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/poles_zeros.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>
#include "random_matrices.hpp"

namespace test_unit_core_poles_zeros {

namespace {

using Eigen::MatrixXcd;
using Eigen::MatrixXd;
using Eigen::VectorXcd;
using Eigen::VectorXd;
using Complex = std::complex<double>;

using sysid::test::match_error;
using sysid::test::randn;
using sysid::test::well_conditioned;
/// Real block-diagonal matrix with the given eigenvalues (pairs as [a b; -b a]).
MatrixXd block_diagonal(const std::vector<Complex>& upper_half_eigenvalues) {
  Eigen::Index n = 0;
  for (const Complex& p : upper_half_eigenvalues) n += p.imag() != 0.0 ? 2 : 1;
  MatrixXd A = MatrixXd::Zero(n, n);
  Eigen::Index k = 0;
  for (const Complex& p : upper_half_eigenvalues) {
    if (p.imag() != 0.0) {
      A.block(k, k, 2, 2) << p.real(), p.imag(), -p.imag(), p.real();
      k += 2;
    } else {
      A(k, k) = p.real();
      k += 1;
    }
  }
  return A;
}

VectorXcd with_conjugates(const std::vector<Complex>& upper) {
  std::vector<Complex> all;
  for (const Complex& p : upper) {
    all.push_back(p);
    if (p.imag() != 0.0) all.push_back(std::conj(p));
  }
  return Eigen::Map<VectorXcd>(all.data(), static_cast<Eigen::Index>(all.size()));
}

/// Applies a random well-conditioned similarity T: (T^-1 A T, T^-1 B, C T, D).
sysid::StateSpace transform(const sysid::StateSpace& s, std::mt19937_64& rng) {
  const MatrixXd T = well_conditioned(rng, s.order());
  const MatrixXd Ti = T.inverse();
  return sysid::StateSpace(Ti * s.A * T, Ti * s.B, s.C * T, s.D, s.Ts);
}

/// sigma_min / sigma_max of the Rosenbrock matrix at lambda: ~eps at a zero.
double rosenbrock_rank_gap(const sysid::StateSpace& s, Complex lambda) {
  const Eigen::Index n = s.order(), m = s.inputs(), l = s.outputs();
  MatrixXcd S(n + l, n + m);
  S << s.A.cast<Complex>() - lambda * MatrixXcd::Identity(n, n), s.B.cast<Complex>(), s.C.cast<Complex>(), s.D.cast<Complex>();
  const VectorXd sv = S.jacobiSvd().singularValues();
  return sv[sv.size() - 1] / sv[0];
}

TEST(CorePolesZeros, PolesOfKnownSystemInAnyBasis) {
  std::mt19937_64 rng(1);
  const std::vector<Complex> p = {{-0.5, 3.0}, {-0.01, 40.0}, {-2.0, 0.0}, {-7.0, 0.0}, {-0.2, 0.5}};
  const sysid::StateSpace s0(block_diagonal(p), randn(rng, 8, 2), randn(rng, 1, 8), MatrixXd::Zero(1, 2), 0.0);
  const sysid::StateSpace s = transform(s0, rng);
  // Eigenvalues of a nonnormal matrix move by ~cond(T)^2 eps ||A||; cond(T) <= 4,
  // ||A|| ~ 40: 1e-11 is a generous bound.
  EXPECT_LT(match_error(with_conjugates(p), sysid::poles(s)), 1e-11);
  // conjugate pairs are exact
  const VectorXcd q = sysid::poles(s);
  for (Eigen::Index i = 0; i < q.size(); ++i)
    if (q[i].imag() != 0.0) {
      EXPECT_EQ(((q.array() - std::conj(q[i])).abs() == 0.0).count(), 1);
    }
}

TEST(CorePolesZeros, PolesOfBadlyScaledMatrix) {
  // diag(10^k) similarity makes entries span 1e-12 .. 1e12; balancing undoes it
  // exactly (powers of two), so the eigenvalues keep their well-scaled accuracy.
  std::mt19937_64 rng(2);
  const std::vector<Complex> p = {{0.9, 0.1}, {0.5, 0.0}, {-0.3, 0.4}, {0.99, 0.0}};
  const MatrixXd A0 = block_diagonal(p);
  const MatrixXd V = well_conditioned(rng, 6);
  VectorXd d(6);
  d << 1e-6, 1e-3, 1.0, 1e2, 1e4, 1e6;
  const MatrixXd A = d.asDiagonal() * V * A0 * V.inverse() * d.cwiseInverse().asDiagonal();
  const sysid::StateSpace s(A, MatrixXd::Ones(6, 1), MatrixXd::Ones(1, 6), MatrixXd::Zero(1, 1), 0.01);
  EXPECT_LT(match_error(with_conjugates(p), sysid::poles(s)), 1e-12);
}

TEST(CorePolesZeros, SisoZerosAreNumeratorRoots) {
  // G(s) = k prod(s - z_i) / prod(s - p_i) realised in controllable form (built
  // here, independently of to_state_space), then scrambled by a similarity.
  std::mt19937_64 rng(3);
  const std::vector<std::vector<Complex>> zero_sets = {
      {},                                       // relative degree 4: D = 0, long chain at infinity
      {{-3.0, 0.0}},                            // relative degree 3
      {{2.0, 0.0}, {-1.0, 4.0}},                // non-minimum phase + pair, relative degree 1
      {{-0.5, 0.0}, {1.5, 0.0}, {-0.2, 2.0}},   // relative degree 0: D != 0
  };
  const std::vector<Complex> pole_set = {{-1.0, 2.0}, {-0.3, 0.0}, {-5.0, 0.0}};  // 4 poles
  const VectorXcd pz = with_conjugates(pole_set);
  Eigen::VectorXcd den_c = Eigen::VectorXcd::Zero(5);
  den_c[0] = 1.0;
  for (Eigen::Index k = 0; k < 4; ++k)
    for (Eigen::Index i = k + 1; i >= 1; --i) den_c[i] -= pz[k] * den_c[i - 1];
  const VectorXd den = den_c.real();
  for (const auto& zs : zero_sets) {
    const VectorXcd zz = with_conjugates(zs);
    Eigen::VectorXcd num_c = Eigen::VectorXcd::Zero(zz.size() + 1);
    num_c[0] = 1.0;
    for (Eigen::Index k = 0; k < zz.size(); ++k)
      for (Eigen::Index i = k + 1; i >= 1; --i) num_c[i] -= zz[k] * num_c[i - 1];
    VectorXd num = VectorXd::Zero(5);
    num.tail(zz.size() + 1) = 2.5 * num_c.real();
    // controllable canonical form of num/den (den monic): D = num_0,
    // C = (num_{n-i} - den_{n-i} num_0) reversed.
    MatrixXd A = MatrixXd::Zero(4, 4);
    A.row(0) = -den.tail(4).transpose();
    A.bottomLeftCorner(3, 3) = MatrixXd::Identity(3, 3);
    MatrixXd B = MatrixXd::Zero(4, 1);
    B(0, 0) = 1.0;
    MatrixXd C(1, 4);
    for (int i = 0; i < 4; ++i) C(0, i) = num[i + 1] - den[i + 1] * num[0];
    const sysid::StateSpace s = transform(sysid::StateSpace(A, B, C, MatrixXd::Constant(1, 1, num[0]), 0.0), rng);
    const VectorXcd z = sysid::transmission_zeros(s);
    // Zeros of a polynomial with O(1) separated roots move by ~1e3 eps * ||S||.
    EXPECT_LT(match_error(zz, z), 1e-10) << "expected " << zz.size() << " zeros, got " << z.transpose();
    if (zz.size() > 0) {
      EXPECT_LT(match_error(zz, sysid::channel_zeros(s, 0, 0)), 1e-10);
    }
  }
}

TEST(CorePolesZeros, KnownMimoExamples) {
  // Skogestad & Postlethwaite, Multivariable Feedback Control, Example 4.11:
  // G(s) = 1/(s+2) [s-1 4; 4.5 2(s-1)] has a transmission zero at s = 4.
  // Minimal realisation: G = diag(1, 2) + [1; -1.5] [-3 4] / (s + 2).
  const sysid::StateSpace g1(MatrixXd::Constant(1, 1, -2.0), (MatrixXd(1, 2) << -3, 4).finished(),
                             (MatrixXd(2, 1) << 1, -1.5).finished(), (MatrixXd(2, 2) << 1, 0, 0, 2).finished(), 0.0);
  const VectorXcd z1 = sysid::transmission_zeros(g1);
  ASSERT_EQ(z1.size(), 1);
  EXPECT_NEAR(std::abs(z1[0] - Complex(4.0, 0.0)), 0.0, 1e-13);

  // Strictly proper (D = 0): G = [1/(s+1) 1/(s+2); 1/(s+3) k/(s+4)],
  // det G = (k (s+2)(s+3) - (s+1)(s+4)) / prod(s+i).
  // k = 1: numerator 2, no finite zeros (a naive QZ of the 6x6 pencil is prone
  // to returning spurious huge ones here). k = 2: zeros of s^2 + 5 s + 8.
  const MatrixXd A = VectorXd::LinSpaced(4, -1.0, -4.0).asDiagonal();
  const MatrixXd B = (MatrixXd(4, 2) << 1, 0, 0, 1, 1, 0, 0, 1).finished();
  std::mt19937_64 rng(4);
  for (double k : {1.0, 2.0}) {
    const MatrixXd C = (MatrixXd(2, 4) << 1, 1, 0, 0, 0, 0, 1, k).finished();
    const sysid::StateSpace g = transform(sysid::StateSpace(A, B, C, MatrixXd::Zero(2, 2), 0.0), rng);
    const VectorXcd z = sysid::transmission_zeros(g);
    if (k == 1.0) {
      EXPECT_EQ(z.size(), 0) << z.transpose();
    } else {
      VectorXcd expected(2);
      expected << Complex(-2.5, std::sqrt(7.0) / 2.0), Complex(-2.5, -std::sqrt(7.0) / 2.0);
      EXPECT_LT(match_error(expected, z), 1e-11) << z.transpose();
    }
  }
}

TEST(CorePolesZeros, RandomSquareSystemsZeroCountAndRankDrop) {
  // Generic square systems: D invertible -> n zeros; D = 0 with C B invertible ->
  // n - m zeros. At each zero the Rosenbrock matrix must lose rank: its
  // sigma_min / sigma_max is at the level of the backward error (~ (n+m) eps
  // times a modest growth), far below the O(1e-2..1) of a generic point.
  std::mt19937_64 rng(5);
  for (Eigen::Index n = 1; n <= 12; ++n)
    for (Eigen::Index m = 1; m <= 3; ++m)
      for (bool with_d : {true, false}) {
        if (!with_d && m > n) continue;
        const MatrixXd D = with_d ? randn(rng, m, m) : MatrixXd::Zero(m, m);
        const sysid::StateSpace s(randn(rng, n, n), randn(rng, n, m), randn(rng, m, n), D, 0.0);
        const VectorXcd z = sysid::transmission_zeros(s);
        EXPECT_EQ(z.size(), with_d ? n : n - m) << "n=" << n << " m=" << m;
        for (Eigen::Index i = 0; i < z.size(); ++i) {
          const double gap = rosenbrock_rank_gap(s, z[i]);
          EXPECT_LT(gap, 1e-12 * std::max(1.0, std::abs(z[i]))) << "n=" << n << " m=" << m << " zero " << z[i];
        }
        // basis invariance
        const double zmax = z.size() > 0 ? z.cwiseAbs().maxCoeff() : 0.0;
        EXPECT_LT(match_error(z, sysid::transmission_zeros(transform(s, rng))), 1e-7 * std::max(1.0, zmax));
      }
}

TEST(CorePolesZeros, ChannelZerosOfMimoSystem) {
  // Every zero of channel (i, j) makes that channel's Rosenbrock matrix lose rank;
  // for the generic random channel (CB != 0) there are n - 1 of them.
  std::mt19937_64 rng(6);
  const sysid::StateSpace s(randn(rng, 5, 5), randn(rng, 5, 2), randn(rng, 3, 5), MatrixXd::Zero(3, 2), 0.01);
  for (Eigen::Index i = 0; i < 3; ++i)
    for (Eigen::Index j = 0; j < 2; ++j) {
      const VectorXcd z = sysid::channel_zeros(s, i, j);
      EXPECT_EQ(z.size(), 4);
      const sysid::StateSpace sij(s.A, s.B.col(j), s.C.row(i), s.D.block(i, j, 1, 1), s.Ts);
      for (Eigen::Index k = 0; k < z.size(); ++k) EXPECT_LT(rosenbrock_rank_gap(sij, z[k]), 1e-12);
    }
}

TEST(CorePolesZeros, RejectsNonSquareAndDegenerate) {
  std::mt19937_64 rng(7);
  const sysid::StateSpace wide(randn(rng, 3, 3), randn(rng, 3, 2), randn(rng, 1, 3), MatrixXd::Zero(1, 2), 0.0);
  EXPECT_THROW(sysid::transmission_zeros(wide), std::invalid_argument);
  EXPECT_THROW(sysid::channel_zeros(wide, 1, 0), std::invalid_argument);
  EXPECT_THROW(sysid::channel_zeros(wide, 0, 2), std::invalid_argument);
  // Two identical outputs: normal rank 1 < 2.
  const MatrixXd c = randn(rng, 1, 3);
  MatrixXd C(2, 3);
  C << c, c;
  const sysid::StateSpace twin(randn(rng, 3, 3), randn(rng, 3, 2), C, MatrixXd::Zero(2, 2), 0.0);
  EXPECT_THROW(sysid::transmission_zeros(twin), sysid::NumericalError);
  // A channel that is identically zero (input does not reach the measured state).
  const sysid::StateSpace zero(MatrixXd::Identity(2, 2) * -1.0, (MatrixXd(2, 1) << 1, 0).finished(),
                               (MatrixXd(1, 2) << 0, 1).finished(), MatrixXd::Zero(1, 1), 0.0);
  EXPECT_THROW(sysid::channel_zeros(zero, 0, 0), sysid::NumericalError);
}

TEST(CorePolesZeros, StaticAndEmpty) {
  const sysid::StateSpace g(MatrixXd(0, 0), MatrixXd(0, 1), MatrixXd(1, 0), MatrixXd::Constant(1, 1, 2.0), 0.0);
  EXPECT_EQ(sysid::poles(g).size(), 0);
  EXPECT_EQ(sysid::transmission_zeros(g).size(), 0);
}

}  // namespace

}  // namespace test_unit_core_poles_zeros
