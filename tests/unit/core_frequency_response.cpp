// Tests for sysid::frequency_response / frequency_response_at
// (include/sysid/core/frequency_response.hpp).
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/simulate.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <complex>
#include <limits>
#include <numbers>
#include <random>
#include "random_matrices.hpp"

namespace test_unit_core_frequency_response {

namespace {

using Eigen::MatrixXcd;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using Complex = std::complex<double>;
constexpr double kEps = std::numeric_limits<double>::epsilon();
using sysid::test::kPi;
using sysid::test::randn;

/// Random stable model: discrete with spectral radius `radius`, or continuous
/// with spectral abscissa -0.1 (A shifted left).
sysid::StateSpace random_stable(std::mt19937_64& rng, Eigen::Index n, Eigen::Index m, Eigen::Index l, double Ts,
                                double radius = 0.95) {
  MatrixXd A = randn(rng, n, n);
  if (Ts > 0) {
    A *= radius / A.eigenvalues().cwiseAbs().maxCoeff();
  } else {
    A -= (A.eigenvalues().real().maxCoeff() + 0.1) * MatrixXd::Identity(n, n);
  }
  return sysid::StateSpace(A, randn(rng, n, m), randn(rng, l, n), randn(rng, l, m), Ts);
}

struct Direct {
  MatrixXcd G;
  double bound;  ///< first-order perturbation bound for a backward-stable method
};

/// Reference C (xI - A)^-1 B + D by a full-pivoting dense solve, plus the error
/// bound of a method whose backward error in A is c n eps ||A||:
///   |dG| <= ||C|| ||R|| (c n eps ||A||) ||R|| ||B||,  R = (xI - A)^-1,
/// with c = 100 covering the Hessenberg reduction and elimination constants.
Direct direct(const sysid::StateSpace& s, Complex x) {
  const Eigen::Index n = s.order();
  MatrixXcd M = -s.A.cast<Complex>();
  M.diagonal().array() += x;
  const MatrixXcd R = M.fullPivLu().inverse();
  Direct d;
  d.G = s.C.cast<Complex>() * R * s.B.cast<Complex>() + s.D.cast<Complex>();
  const double r = R.operatorNorm();
  d.bound = 100.0 * static_cast<double>(n) * kEps *
                (s.C.operatorNorm() * r * (s.A.operatorNorm() + std::abs(x)) * r * s.B.operatorNorm()) +
            kEps * s.D.norm();
  return d;
}

TEST(CoreFrequencyResponse, MatchesDirectEvaluationSweepMimo) {
  std::mt19937_64 rng(424242);
  for (double Ts : {0.0, 1e-3}) {
    for (Eigen::Index n = 1; n <= 12; ++n)
      for (Eigen::Index m = 1; m <= 3; ++m)
        for (Eigen::Index l = 1; l <= 3; ++l) {
          const sysid::StateSpace s = random_stable(rng, n, m, l, Ts);
          // Grid plus the frequencies of the poles themselves (near-resonant points).
          const double fmax = Ts > 0 ? 0.5 / Ts : 10.0;
          VectorXd f = VectorXd::LinSpaced(40, 0.0, fmax);
          const Eigen::VectorXcd p = s.A.eigenvalues();
          VectorXd fp(p.size());
          for (Eigen::Index i = 0; i < p.size(); ++i)
            fp[i] = (Ts > 0 ? std::arg(p[i]) / Ts : p[i].imag()) / (2.0 * kPi);
          VectorXd all(f.size() + fp.size());
          all << f, fp;
          const std::vector<MatrixXcd> G = sysid::frequency_response(s, all);
          ASSERT_EQ(G.size(), static_cast<std::size_t>(all.size()));
          for (Eigen::Index i = 0; i < all.size(); ++i) {
            const Complex x = Ts > 0 ? std::polar(1.0, 2.0 * kPi * all[i] * Ts) : Complex(0.0, 2.0 * kPi * all[i]);
            const Direct d = direct(s, x);
            ASSERT_EQ(G[i].rows(), l);
            ASSERT_EQ(G[i].cols(), m);
            EXPECT_LE((G[i] - d.G).norm(), d.bound) << "Ts=" << Ts << " n=" << n << " m=" << m << " l=" << l << " f=" << all[i];
            // the single-point variant agrees too
            EXPECT_LE((sysid::frequency_response_at(s, x) - d.G).norm(), d.bound);
          }
        }
  }
}

TEST(CoreFrequencyResponse, EqualsDtftOfImpulseResponse) {
  // For a stable discrete model G(e^jw) = sum_k h_k e^(-jwk), h_0 = D, h_k = C A^(k-1) B.
  // With spectral radius 0.8 the tail after K terms is O(0.8^K * transient growth);
  // K = 400 puts it far below rounding.
  std::mt19937_64 rng(99);
  for (Eigen::Index n : {1, 3, 8}) {
    const sysid::StateSpace s = random_stable(rng, n, 2, 2, 0.01, 0.8);
    const Eigen::Index K = 400;
    std::vector<MatrixXd> h(K, MatrixXd(2, 2));
    for (Eigen::Index j = 0; j < 2; ++j) {
      MatrixXd u = MatrixXd::Zero(K, 2);
      u(0, j) = 1.0;
      const MatrixXd y = sysid::simulate(s, u);
      for (Eigen::Index k = 0; k < K; ++k) h[k].col(j) = y.row(k).transpose();
    }
    double hsum = 0.0;
    for (const MatrixXd& hk : h) hsum += hk.norm();
    const VectorXd f = VectorXd::LinSpaced(33, -50.0, 50.0);  // -Nyquist .. Nyquist
    const std::vector<MatrixXcd> G = sysid::frequency_response(s, f);
    for (Eigen::Index i = 0; i < f.size(); ++i) {
      MatrixXcd dtft = MatrixXcd::Zero(2, 2);
      for (Eigen::Index k = 0; k < K; ++k) dtft += h[k].cast<Complex>() * std::polar(1.0, -2.0 * kPi * f[i] * 0.01 * static_cast<double>(k));
      // summation error of K terms of size <= |h_k|: K eps sum|h_k|
      EXPECT_LE((G[i] - dtft).norm(), static_cast<double>(K) * kEps * hsum) << "n=" << n << " f=" << f[i];
    }
  }
}

TEST(CoreFrequencyResponse, FirstOrderAnalytic) {
  // continuous b / (s + a); discrete b / (z - a)
  const double a = 3.0, b = 2.0;
  const sysid::StateSpace c(MatrixXd::Constant(1, 1, -a), MatrixXd::Constant(1, 1, b), MatrixXd::Ones(1, 1),
                            MatrixXd::Zero(1, 1), 0.0);
  const sysid::StateSpace d(MatrixXd::Constant(1, 1, 0.5), MatrixXd::Constant(1, 1, b), MatrixXd::Ones(1, 1),
                            MatrixXd::Constant(1, 1, 0.25), 0.1);
  const VectorXd f = VectorXd::LinSpaced(11, 0.0, 5.0);
  const auto Gc = sysid::frequency_response(c, f);
  const auto Gd = sysid::frequency_response(d, f);
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    const Complex s(0.0, 2.0 * kPi * f[i]);
    const Complex z = std::polar(1.0, 2.0 * kPi * f[i] * 0.1);
    EXPECT_NEAR(std::abs(Gc[i](0, 0) - b / (s + a)), 0.0, 1e-15);
    EXPECT_NEAR(std::abs(Gd[i](0, 0) - (0.25 + b / (z - 0.5))), 0.0, 1e-14);
  }
}

TEST(CoreFrequencyResponse, SymmetryAndPeriodicity) {
  std::mt19937_64 rng(5);
  const sysid::StateSpace s = random_stable(rng, 6, 2, 3, 0.002);
  VectorXd f(3), g(3), h(3);
  f << 13.0, 77.0, 201.0;
  g = -f;
  h = f.array() + 500.0;  // + 1/Ts
  const auto Gf = sysid::frequency_response(s, f), Gg = sysid::frequency_response(s, g), Gh = sysid::frequency_response(s, h);
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT((Gg[i] - Gf[i].conjugate()).norm(), 1e-11 * Gf[i].norm());
    EXPECT_LT((Gh[i] - Gf[i]).norm(), 1e-9 * Gf[i].norm());  // z differs by rounding of 2 pi f Ts (~1e-13 rad)
  }
}

TEST(CoreFrequencyResponse, StaticGainAndEmptyGrid) {
  const sysid::StateSpace g(MatrixXd(0, 0), MatrixXd(0, 2), MatrixXd(1, 0), (MatrixXd(1, 2) << 3, -4).finished(), 0.0);
  const auto G = sysid::frequency_response(g, VectorXd::LinSpaced(3, 0.0, 1.0));
  ASSERT_EQ(G.size(), 3u);
  EXPECT_EQ(G[2](0, 1), Complex(-4.0, 0.0));
  EXPECT_TRUE(sysid::frequency_response(g, VectorXd()).empty());
}

}  // namespace

}  // namespace test_unit_core_frequency_response
