// Tests for sysid::c2d_zoh / d2c_zoh / c2d_foh (include/sysid/core/discretize.hpp).
#include <sysid/core/discretize.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/simulate.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <stdexcept>
#include "random_matrices.hpp"

namespace test_unit_core_discretize {

namespace {

using Eigen::MatrixXcd;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using Complex = std::complex<double>;
using sysid::test::kPi;
using sysid::test::randn;
using sysid::test::well_conditioned;

/// Random stable continuous model whose poles satisfy |Im s| Ts < 0.8 pi (no
/// aliasing, so d2c can recover it) and Re s in [-0.5, -0.01] / Ts.
sysid::StateSpace random_continuous(std::mt19937_64& rng, Eigen::Index n, Eigen::Index m, Eigen::Index l, double Ts) {
  std::uniform_real_distribution<double> re(-0.5, -0.01), im(0.01, 0.8 * kPi);
  MatrixXd A0 = MatrixXd::Zero(n, n);
  Eigen::Index k = 0;
  while (k < n) {
    if (k + 1 < n && (k % 3 != 2)) {  // mostly pairs, some real poles
      const double a = re(rng) / Ts, b = im(rng) / Ts;
      A0.block(k, k, 2, 2) << a, b, -b, a;
      k += 2;
    } else {
      A0(k, k) = re(rng) / Ts;
      k += 1;
    }
  }
  const MatrixXd T = well_conditioned(rng, n);
  return sysid::StateSpace(T * A0 * T.inverse(), randn(rng, n, m), randn(rng, l, n), randn(rng, l, m), 0.0);
}

double max_rel_frf_diff(const sysid::StateSpace& a, const sysid::StateSpace& b, const VectorXd& f) {
  const auto Ga = sysid::frequency_response(a, f), Gb = sysid::frequency_response(b, f);
  double worst = 0.0;
  for (std::size_t i = 0; i < Ga.size(); ++i) worst = std::max(worst, (Ga[i] - Gb[i]).norm() / Gb[i].norm());
  return worst;
}

TEST(CoreDiscretize, FirstOrderAnalytic) {
  // dx/dt = -a x + b u, y = c x + d u  ->  Ad = e^(-a Ts), Bd = b (1 - e^(-a Ts)) / a.
  // Basis-invariant checks: the pole and the Markov parameters h0 = d, h1 = c Bd.
  const double a = 7.0, b = 3.0, c = 0.5, d = 0.25, Ts = 0.05;
  const sysid::StateSpace sc(MatrixXd::Constant(1, 1, -a), MatrixXd::Constant(1, 1, b), MatrixXd::Constant(1, 1, c),
                             MatrixXd::Constant(1, 1, d), 0.0);
  const sysid::StateSpace sd = sysid::c2d_zoh(sc, Ts);
  EXPECT_EQ(sd.Ts, Ts);
  EXPECT_NEAR(sysid::poles(sd)[0].real(), std::exp(-a * Ts), 1e-15);
  EXPECT_NEAR((sd.C * sd.B)(0, 0), c * b * -std::expm1(-a * Ts) / a, 1e-15);
  EXPECT_EQ(sd.D(0, 0), d);
}

TEST(CoreDiscretize, IntegratorNeedsNoInverse) {
  // dx/dt = u: Ad = 1, Bd = Ts exactly (A is singular; the block exponential copes).
  const sysid::StateSpace sc(MatrixXd::Zero(1, 1), MatrixXd::Ones(1, 1), MatrixXd::Ones(1, 1), MatrixXd::Zero(1, 1), 0.0);
  const sysid::StateSpace sd = sysid::c2d_zoh(sc, 0.1);
  EXPECT_NEAR(sd.A(0, 0), 1.0, 1e-15);
  EXPECT_NEAR(sd.C(0, 0) * sd.B(0, 0), 0.1, 1e-15);
  // and back
  const sysid::StateSpace back = sysid::d2c_zoh(sd);
  EXPECT_NEAR(back.A(0, 0), 0.0, 1e-14);
  EXPECT_NEAR(back.C(0, 0) * back.B(0, 0), 1.0, 1e-13);
}

TEST(CoreDiscretize, StepResponseSamplesContinuousStepExactly) {
  // Mass-spring-damper x'' + 2 zeta wn x' + wn^2 x = wn^2 u (unit DC gain). Under
  // ZOH a step input is exact, so the discrete step response equals the analytic
  // continuous one at t = k Ts.
  const double wn = 2.0 * kPi * 12.0, zeta = 0.05, Ts = 1e-3;
  const MatrixXd A = (MatrixXd(2, 2) << 0, 1, -wn * wn, -2 * zeta * wn).finished();
  const sysid::StateSpace sc(A, (MatrixXd(2, 1) << 0, wn * wn).finished(), (MatrixXd(1, 2) << 1, 0).finished(),
                             MatrixXd::Zero(1, 1), 0.0);
  const sysid::StateSpace sd = sysid::c2d_zoh(sc, Ts);
  const Eigen::Index N = 2000;
  const MatrixXd y = sysid::simulate(sd, MatrixXd::Ones(N, 1));
  const double wd = wn * std::sqrt(1 - zeta * zeta);
  double worst = 0.0;
  for (Eigen::Index k = 0; k < N; ++k) {
    const double t = static_cast<double>(k) * Ts;
    const double exact = 1.0 - std::exp(-zeta * wn * t) * (std::cos(wd * t) + zeta / std::sqrt(1 - zeta * zeta) * std::sin(wd * t));
    worst = std::max(worst, std::abs(y(k, 0) - exact));
  }
  // expm to ~eps relative, then 2000 steps of a recursion with |z| ~ 0.996:
  // accumulated rounding ~ 1e-13.
  EXPECT_LT(worst, 1e-11);
}

TEST(CoreDiscretize, FirstOrderHoldIsExactForPiecewiseLinearInputs) {
  // A two-input, two-output oscillator driven by inputs that are straight lines
  // between their samples: the FOH model's outputs equal the continuous ones at
  // the sample instants, integrated here independently by RK4 with 100 steps per
  // sample (local error ~ (w h)^5 ~ 1e-16 at w h = 7.5e-4).
  const double wn = 2.0 * kPi * 12.0, zeta = 0.05, Ts = 1e-3;
  const MatrixXd A = (MatrixXd(2, 2) << 0, 1, -wn * wn, -2 * zeta * wn).finished();
  const MatrixXd B = (MatrixXd(2, 2) << 0, 1, wn * wn, -3).finished();
  const MatrixXd C = (MatrixXd(2, 2) << 1, 0, 0.2, 0.01).finished();
  const MatrixXd D = (MatrixXd(2, 2) << 0, 0, 0.5, 0).finished();
  const sysid::StateSpace sc(A, B, C, D, 0.0);
  const sysid::StateSpace sd = sysid::c2d_foh(sc, Ts);
  std::mt19937_64 rng(4);
  const Eigen::Index N = 300;
  MatrixXd u = randn(rng, N, 2);
  // The FOH state is xi = x - G2 u: a simulation from xi(0) = 0 starts at x(0) =
  // G2 u(0), which is the continuous x(0) = 0 when u(0) = 0.
  u.row(0).setZero();
  const MatrixXd y = sysid::simulate(sd, u);
  const int sub = 100;
  const double h = Ts / sub;
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  double worst = 0.0, scale = 0.0;
  for (Eigen::Index k = 0; k < N; ++k) {
    const Eigen::Vector2d exact = C * x + D * u.row(k).transpose();
    worst = std::max(worst, (y.row(k).transpose() - exact).cwiseAbs().maxCoeff());
    scale = std::max(scale, exact.cwiseAbs().maxCoeff());
    if (k + 1 == N) break;
    const Eigen::Vector2d u0 = u.row(k).transpose(), slope = (u.row(k + 1) - u.row(k)).transpose() / Ts;
    const auto f = [&](const Eigen::Vector2d& xs, double tau) -> Eigen::Vector2d { return A * xs + B * (u0 + slope * tau); };
    for (int j = 0; j < sub; ++j) {
      const double t = j * h;
      const Eigen::Vector2d k1 = f(x, t), k2 = f(x + 0.5 * h * k1, t + 0.5 * h), k3 = f(x + 0.5 * h * k2, t + 0.5 * h),
                            k4 = f(x + h * k3, t + h);
      x += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
  }
  EXPECT_LT(worst, 1e-10 * scale) << worst << " of " << scale;
  // ZOH, on the same samples, is visibly off (the hold lags by half a sample).
  const MatrixXd y_zoh = sysid::simulate(sysid::c2d_zoh(sc, Ts), u);
  EXPECT_GT((y_zoh - y).cwiseAbs().maxCoeff(), 1e-3 * scale);
}

TEST(CoreDiscretize, FirstOrderHoldKeepsPolesAndDcGain) {
  std::mt19937_64 rng(12);
  const double Ts = 1e-3;
  for (Eigen::Index n = 1; n <= 6; ++n) {
    const sysid::StateSpace sc = random_continuous(rng, n, 2, 3, Ts);
    const sysid::StateSpace foh = sysid::c2d_foh(sc, Ts), zoh = sysid::c2d_zoh(sc, Ts);
    EXPECT_NEAR((foh.A - zoh.A).norm(), 0.0, 1e-14 * zoh.A.norm()) << n;
    // G(z = 1) of the hold = G(s = 0): a constant input is held exactly by both.
    EXPECT_LT(max_rel_frf_diff(foh, sc, VectorXd::Zero(1)), 1e-10) << n;
    EXPECT_EQ(foh.input_names, sc.input_names);
  }
  // An integrator: FOH of 1/s is the trapezoidal rule, (Ts/2) (z + 1) / (z - 1).
  const sysid::StateSpace integrator(MatrixXd::Zero(1, 1), MatrixXd::Ones(1, 1), MatrixXd::Ones(1, 1), MatrixXd::Zero(1, 1), 0.0);
  const sysid::StateSpace trap = sysid::c2d_foh(integrator, 0.1);
  EXPECT_NEAR(trap.D(0, 0), 0.05, 1e-15);                        // h0 = Ts/2
  EXPECT_NEAR(trap.C(0, 0) * trap.B(0, 0), 0.1, 1e-15);          // h1 = Ts
  EXPECT_NEAR(trap.C(0, 0) * trap.A(0, 0) * trap.B(0, 0), 0.1, 1e-15);  // h2 = Ts
  EXPECT_THROW(sysid::c2d_foh(trap, 0.1), std::invalid_argument);
  EXPECT_THROW(sysid::c2d_foh(integrator, 0.0), std::invalid_argument);
}

TEST(CoreDiscretize, RoundTripRecoversContinuousFrequencyResponse) {
  std::mt19937_64 rng(8);
  const double Ts = 1e-3;
  const VectorXd f = VectorXd::LinSpaced(60, 0.0, 3000.0);  // beyond Nyquist too: it is the continuous FRF
  for (Eigen::Index n = 1; n <= 10; ++n)
    for (Eigen::Index m = 1; m <= 2; ++m)
      for (Eigen::Index l = 1; l <= 2; ++l) {
        const sysid::StateSpace sc = random_continuous(rng, n, m, l, Ts);
        const sysid::StateSpace back = sysid::d2c_zoh(sysid::c2d_zoh(sc, Ts));
        EXPECT_EQ(back.Ts, 0.0);
        // expm and logm are each accurate to ~cond * eps with cond ~ 1e2..1e3 for
        // these well-separated poles: 1e-9 relative leaves margin.
        EXPECT_LT(max_rel_frf_diff(back, sc, f), 1e-9) << "n=" << n << " m=" << m << " l=" << l;
      }
}

TEST(CoreDiscretize, DiscretePolesAreExponentialsOfContinuousPoles) {
  std::mt19937_64 rng(9);
  const double Ts = 0.01;
  const sysid::StateSpace sc = random_continuous(rng, 7, 1, 1, Ts);
  const Eigen::VectorXcd pc = sysid::poles(sc), pd = sysid::poles(sysid::c2d_zoh(sc, Ts));
  ASSERT_EQ(pc.size(), pd.size());
  for (Eigen::Index i = 0; i < pc.size(); ++i) {
    const Complex target = std::exp(pc[i] * Ts);
    EXPECT_LT((pd.array() - target).abs().minCoeff(), 1e-12) << target;
  }
}

TEST(CoreDiscretize, RejectsViolatedPreconditions) {
  const sysid::StateSpace sc(MatrixXd::Constant(1, 1, -1.0), MatrixXd::Ones(1, 1), MatrixXd::Ones(1, 1), MatrixXd::Zero(1, 1), 0.0);
  EXPECT_THROW(sysid::c2d_zoh(sc, 0.0), std::invalid_argument);
  EXPECT_THROW(sysid::c2d_zoh(sc, -1.0), std::invalid_argument);
  EXPECT_THROW(sysid::d2c_zoh(sc), std::invalid_argument);
  const sysid::StateSpace sd = sysid::c2d_zoh(sc, 0.1);
  EXPECT_THROW(sysid::c2d_zoh(sd, 0.1), std::invalid_argument);
  // A negative real pole (or one at 0) has no real logarithm.
  for (double p : {-0.5, 0.0}) {
    const sysid::StateSpace bad(MatrixXd::Constant(1, 1, p), MatrixXd::Ones(1, 1), MatrixXd::Ones(1, 1), MatrixXd::Zero(1, 1), 0.1);
    EXPECT_THROW(sysid::d2c_zoh(bad), sysid::NumericalError) << p;
  }
  // A complex pair near the negative real axis is fine (Im s just below pi / Ts).
  const double r = 0.9, th = 0.95 * kPi;
  const sysid::StateSpace pair((MatrixXd(2, 2) << r * std::cos(th), r * std::sin(th), -r * std::sin(th), r * std::cos(th)).finished(),
                               MatrixXd::Ones(2, 1), MatrixXd::Ones(1, 2), MatrixXd::Zero(1, 1), 0.1);
  EXPECT_NO_THROW(sysid::d2c_zoh(pair));
}

TEST(CoreDiscretize, SubnormalSampleTimeIsANumericalErrorNotACrash) {
  // Found by fuzzing the augmented-model reader: Ts = 5e-324 made log(Phi) / Ts
  // infinite and the StateSpace constructor threw an unexpected invalid_argument.
  const sysid::StateSpace tiny(MatrixXd::Constant(1, 1, 0.5), MatrixXd::Ones(1, 1), MatrixXd::Ones(1, 1),
                               MatrixXd::Zero(1, 1), 5e-324);
  EXPECT_THROW(sysid::d2c_zoh(tiny), sysid::NumericalError);
}

}  // namespace

}  // namespace test_unit_core_discretize
