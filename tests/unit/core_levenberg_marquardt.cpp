// Tests of core/levenberg_marquardt.hpp on small dense problems: the Rosenbrock
// valley and an exponential curve fit reach their known minima, a zero-residual
// start stops at once, rank-deficient Jacobians (a repeated and a zero column) give
// finite minimum-cost answers, the iteration limit and the domain constraint are
// honoured, a step-by-step (resumed) run is bit-identical to an uninterrupted one,
// and a problem whose every step leaves the domain ends as `failed`.
#include <sysid/core/levenberg_marquardt.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace test_unit_core_levenberg_marquardt {

using sysid::LevenbergMarquardt;

namespace {

/// A dense problem: r(x) and J(x) from callables, the factor of [J r] by a
/// Householder QR (zero rows appended when N < n + 1), an optional domain.
class DenseProblem : public LevenbergMarquardt::Problem {
 public:
  using Residual = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;
  using Jacobian = std::function<Eigen::MatrixXd(const Eigen::VectorXd&)>;
  using Domain = std::function<bool(const Eigen::VectorXd&)>;

  DenseProblem(Residual r, Jacobian J, Eigen::VectorXd x0, Domain domain = {})
      : m_r(std::move(r)), m_J(std::move(J)), m_domain(std::move(domain)), m_x(std::move(x0)) {
    m_N = m_r(m_x).size();
  }

  Eigen::Index residual_count() const override { return m_N; }
  Eigen::Index parameter_count() const override { return m_x.size(); }
  Eigen::VectorXd parameters() const override { return m_x; }
  double cost() override { return 0.5 * m_r(m_x).squaredNorm(); }
  Eigen::MatrixXd jacobian_factor() override {
    const Eigen::Index n = m_x.size();
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(std::max(m_N, n + 1), n + 1);
    M.topLeftCorner(m_N, n) = m_J(m_x);
    M.col(n).head(m_N) = m_r(m_x);
    const Eigen::MatrixXd qr = M.householderQr().matrixQR();
    return qr.topRows(n + 1).triangularView<Eigen::Upper>();
  }
  bool set_candidate(const Eigen::VectorXd& x) override {
    m_candidate = x;
    return !m_domain || m_domain(x);
  }
  double candidate_cost() override { return 0.5 * m_r(m_candidate).squaredNorm(); }
  void accept_candidate() override {
    m_x = m_candidate;
    m_accepted.push_back(m_x);
  }

  const Eigen::VectorXd& x() const { return m_x; }
  const std::vector<Eigen::VectorXd>& accepted() const { return m_accepted; }

 private:
  Residual m_r;
  Jacobian m_J;
  Domain m_domain;
  Eigen::VectorXd m_x, m_candidate;
  Eigen::Index m_N = 0;
  std::vector<Eigen::VectorXd> m_accepted;
};

/// Rosenbrock's valley as least squares: r = [10 (x2 - x1^2), 1 - x1], minimum 0 at (1, 1).
DenseProblem rosenbrock(double x1, double x2) {
  return DenseProblem(
      [](const Eigen::VectorXd& x) { return Eigen::Vector2d(10.0 * (x(1) - x(0) * x(0)), 1.0 - x(0)).eval(); },
      [](const Eigen::VectorXd& x) {
        Eigen::MatrixXd J(2, 2);
        J << -20.0 * x(0), 10.0, -1.0, 0.0;
        return J;
      },
      Eigen::Vector2d(x1, x2));
}

/// y(t) = a exp(-b t) + c at t = 0, 0.1, ..., 4.9, plus `noise` times seeded N(0, 1).
struct Decay {
  Eigen::VectorXd t, y;
  Eigen::VectorXd residual(const Eigen::VectorXd& p) const {
    return ((p(0) * (-p(1) * t.array()).exp() + p(2)) - y.array()).matrix();
  }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& p) const {
    Eigen::MatrixXd J(t.size(), 3);
    J.col(0) = (-p(1) * t.array()).exp().matrix();
    J.col(1) = (-p(0) * t.array() * (-p(1) * t.array()).exp()).matrix();
    J.col(2).setOnes();
    return J;
  }
};

Decay decay(double noise) {
  Decay d;
  d.t = Eigen::VectorXd::LinSpaced(50, 0.0, 4.9);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  d.y.resize(50);
  for (Eigen::Index k = 0; k < 50; ++k) d.y(k) = 2.5 * std::exp(-1.3 * d.t(k)) + 0.4 + noise * g(rng);
  return d;
}

DenseProblem decay_problem(const Decay& d, Eigen::Vector3d start) {
  return DenseProblem([d](const Eigen::VectorXd& p) { return d.residual(p); },
                      [d](const Eigen::VectorXd& p) { return d.jacobian(p); }, start);
}

}  // namespace

TEST(LevenbergMarquardtSolver, RosenbrockReachesItsMinimum) {
  DenseProblem problem = rosenbrock(-1.2, 1.0);
  const LevenbergMarquardt::Summary s = LevenbergMarquardt::solve(problem);
  EXPECT_EQ(s.status, LevenbergMarquardt::Status::converged) << s.brief_report();
  EXPECT_NEAR(problem.x()(0), 1.0, 1e-8);
  EXPECT_NEAR(problem.x()(1), 1.0, 1e-8);
  EXPECT_LT(s.final_cost, 1e-20);
  EXPECT_DOUBLE_EQ(s.initial_cost, 0.5 * (100.0 * 0.44 * 0.44 + 2.2 * 2.2));  // r = [-4.4, 2.2]
  EXPECT_GT(s.iterations, 1);
  // Every accepted step lowers the cost: the history is strictly decreasing.
  ASSERT_EQ(s.cost_history.size(), problem.accepted().size() + 1);
  for (std::size_t k = 1; k < s.cost_history.size(); ++k) EXPECT_LT(s.cost_history[k], s.cost_history[k - 1]) << k;
  EXPECT_EQ(s.cost_history.back(), s.final_cost);
  EXPECT_NE(s.brief_report().find("converged"), std::string::npos);
}

TEST(LevenbergMarquardtSolver, CurveFitReachesTheKnownMinimum) {
  // Noise-free: the exact parameters, cost at rounding level.
  const Decay exact = decay(0.0);
  DenseProblem clean = decay_problem(exact, Eigen::Vector3d(1.0, 0.5, 0.0));
  const LevenbergMarquardt::Summary s0 = LevenbergMarquardt::solve(clean);
  EXPECT_EQ(s0.status, LevenbergMarquardt::Status::converged) << s0.brief_report();
  EXPECT_NEAR(clean.x()(0), 2.5, 1e-9);
  EXPECT_NEAR(clean.x()(1), 1.3, 1e-9);
  EXPECT_NEAR(clean.x()(2), 0.4, 1e-9);
  // With noise the minimum is not the truth: it is where J^T r = 0, below the cost
  // at the true parameters, and within a few standard errors of them. The run
  // stops (default step_significance_tolerance = 0.1) once the remaining
  // Gauss-Newton step is shorter than 0.1 standard deviations of the estimate.
  const Decay noisy = decay(0.02);
  DenseProblem fit = decay_problem(noisy, Eigen::Vector3d(1.0, 0.5, 0.0));
  const LevenbergMarquardt::Summary s = LevenbergMarquardt::solve(fit);
  EXPECT_EQ(s.status, LevenbergMarquardt::Status::converged) << s.brief_report();
  const Eigen::VectorXd r = noisy.residual(fit.x());
  const Eigen::MatrixXd J = noisy.jacobian(fit.x());
  const Eigen::VectorXd gn_step = -(J.transpose() * J).ldlt().solve(J.transpose() * r);
  const double sigma2 = r.squaredNorm() / 47.0;  // 2 F / (N - n)
  EXPECT_LE((J * gn_step).squaredNorm() / sigma2, 0.01 * (1.0 + 1e-6));
  EXPECT_LT((J.transpose() * r).cwiseAbs().maxCoeff(), 1e-3 * J.norm() * r.norm());
  EXPECT_LE(s.final_cost, 0.5 * noisy.residual(Eigen::Vector3d(2.5, 1.3, 0.4)).squaredNorm());
  EXPECT_NEAR(s.final_cost, 0.5 * r.squaredNorm(), 1e-15);
  // The factor at the end is that of [J r] there: R11^T R11 = J^T J.
  const Eigen::MatrixXd R11 = s.r.topLeftCorner(3, 3).triangularView<Eigen::Upper>();
  EXPECT_LT(((R11.transpose() * R11) - J.transpose() * J).norm(), 1e-10 * (J.transpose() * J).norm());
  const Eigen::MatrixXd cov = 2.0 * s.final_cost / 47.0 * (J.transpose() * J).inverse();
  for (int k = 0; k < 3; ++k)
    EXPECT_LT(std::abs(fit.x()(k) - Eigen::Vector3d(2.5, 1.3, 0.4)(k)), 5.0 * std::sqrt(cov(k, k))) << k;
}

TEST(LevenbergMarquardtSolver, ZeroResidualStartStopsAtOnce) {
  // A linear problem started at its exact solution: J^T r = 0, no step taken.
  const Eigen::Matrix<double, 4, 2> A = (Eigen::Matrix<double, 4, 2>() << 1, 2, 3, 4, 5, 6, 7, 9).finished();
  const Eigen::Vector2d solution(0.5, -1.5);
  const Eigen::Vector4d b = A * solution;
  DenseProblem problem([A, b](const Eigen::VectorXd& x) { return (A * x - b).eval(); },
                       [A](const Eigen::VectorXd&) { return Eigen::MatrixXd(A); }, solution);
  const LevenbergMarquardt::Summary s = LevenbergMarquardt::solve(problem);
  EXPECT_EQ(s.status, LevenbergMarquardt::Status::converged);
  EXPECT_EQ(s.termination, "gradient below tolerance");
  EXPECT_EQ(s.iterations, 0);
  EXPECT_EQ(s.final_cost, 0.0);
  EXPECT_TRUE(problem.accepted().empty());
  EXPECT_EQ(problem.x(), solution);
}

TEST(LevenbergMarquardtSolver, SingularJacobianGivesAFiniteMinimum) {
  // r depends on x1 + x2 only (two equal columns): min over s = x1 + x2 of
  // 2 (s - 2)^2 + (2 s - 3)^2 at s = 5/3, cost 1/6. The damping keeps the step
  // finite; the solver must not fail or produce NaN.
  DenseProblem repeated(
      [](const Eigen::VectorXd& x) {
        const double s = x(0) + x(1);
        return Eigen::Vector3d(s - 2.0, s - 2.0, 2.0 * s - 3.0).eval();
      },
      [](const Eigen::VectorXd&) {
        Eigen::MatrixXd J(3, 2);
        J << 1, 1, 1, 1, 2, 2;
        return J;
      },
      Eigen::Vector2d(4.0, -7.0));
  const LevenbergMarquardt::Summary s = LevenbergMarquardt::solve(repeated);
  EXPECT_NE(s.status, LevenbergMarquardt::Status::failed) << s.brief_report();
  ASSERT_TRUE(repeated.x().allFinite());
  EXPECT_NEAR(repeated.x().sum(), 5.0 / 3.0, 1e-8);
  EXPECT_NEAR(s.final_cost, 1.0 / 6.0, 1e-12);
  // The direction the data do not see (x1 - x2) is left where it started: the
  // damped steps are along (1, 1).
  EXPECT_NEAR(repeated.x()(0) - repeated.x()(1), 11.0, 1e-8);

  // A zero column (x2 has no effect): x1 found, x2 untouched.
  DenseProblem zero_column([](const Eigen::VectorXd& x) { return Eigen::Vector2d(x(0) - 1.0, 2.0 * x(0) - 2.0).eval(); },
                           [](const Eigen::VectorXd&) {
                             Eigen::MatrixXd J(2, 2);
                             J << 1, 0, 2, 0;
                             return J;
                           },
                           Eigen::Vector2d(-3.0, 0.25));
  const LevenbergMarquardt::Summary z = LevenbergMarquardt::solve(zero_column);
  EXPECT_EQ(z.status, LevenbergMarquardt::Status::converged) << z.brief_report();
  EXPECT_NEAR(zero_column.x()(0), 1.0, 1e-10);
  EXPECT_EQ(zero_column.x()(1), 0.25);
}

TEST(LevenbergMarquardtSolver, IterationLimitIsAStatus) {
  DenseProblem problem = rosenbrock(-1.2, 1.0);
  LevenbergMarquardt::Options o;
  o.max_iterations = 3;
  const LevenbergMarquardt::Summary s = LevenbergMarquardt::solve(problem, o);
  EXPECT_EQ(s.status, LevenbergMarquardt::Status::max_iterations);
  EXPECT_EQ(s.termination, "reached max_iterations (3)");
  EXPECT_EQ(s.iterations, 3);
  EXPECT_LT(s.final_cost, s.initial_cost);
  EXPECT_GT(s.final_cost, 1e-6);  // Rosenbrock from (-1.2, 1) needs more than 3 steps
  // max_iterations = 0: no iteration, the start's cost and factor.
  DenseProblem still = rosenbrock(-1.2, 1.0);
  o.max_iterations = 0;
  const LevenbergMarquardt::Summary s0 = LevenbergMarquardt::solve(still, o);
  EXPECT_EQ(s0.status, LevenbergMarquardt::Status::max_iterations);
  EXPECT_EQ(s0.iterations, 0);
  EXPECT_EQ(s0.final_cost, s0.initial_cost);
  EXPECT_EQ(s0.r.rows(), 3);
}

TEST(LevenbergMarquardtSolver, ResumedRunEqualsOneRun) {
  // pem races starts one iteration at a time and continues the best: a run
  // interrupted at any point must end exactly (bit for bit) where one
  // uninterrupted run ends.
  DenseProblem once = rosenbrock(-1.2, 1.0);
  const LevenbergMarquardt::Summary whole = LevenbergMarquardt::solve(once);

  DenseProblem pieces = rosenbrock(-1.2, 1.0);
  LevenbergMarquardt lm(pieces);
  lm.iterate_up_to(2);
  EXPECT_EQ(lm.iterations(), 2);
  EXPECT_FALSE(lm.ended());
  const LevenbergMarquardt::Summary middle = lm.finish();  // a look at the run does not disturb it
  EXPECT_EQ(middle.iterations, 2);
  EXPECT_EQ(middle.status, LevenbergMarquardt::Status::max_iterations);
  lm.iterate_up_to(5);
  while (lm.iterate()) {
  }
  EXPECT_TRUE(lm.ended());
  EXPECT_FALSE(lm.iterate());  // an ended run stays ended
  const LevenbergMarquardt::Summary resumed = lm.finish();

  EXPECT_EQ(resumed.status, whole.status);
  EXPECT_EQ(resumed.termination, whole.termination);
  EXPECT_EQ(resumed.iterations, whole.iterations);
  EXPECT_EQ(resumed.final_cost, whole.final_cost);
  EXPECT_EQ(resumed.cost_history, whole.cost_history);
  EXPECT_EQ(resumed.damping, whole.damping);
  EXPECT_EQ(pieces.x(), once.x());
  EXPECT_EQ(resumed.r, whole.r);
  EXPECT_EQ(lm.converged(), whole.status == LevenbergMarquardt::Status::converged);
  EXPECT_EQ(lm.current_cost(), whole.final_cost);
}

TEST(LevenbergMarquardtSolver, StepsStayInTheDomain) {
  // min (x - 2)^2 over the domain x < 1.5: steps towards 2 are shortened, never taken
  // outside; the run ends just below the boundary.
  DenseProblem problem([](const Eigen::VectorXd& x) { return Eigen::VectorXd::Constant(1, x(0) - 2.0); },
                       [](const Eigen::VectorXd&) { return Eigen::MatrixXd::Ones(1, 1); }, Eigen::VectorXd::Zero(1),
                       [](const Eigen::VectorXd& x) { return x(0) < 1.5; });
  LevenbergMarquardt::Options o;
  o.max_iterations = 200;
  const LevenbergMarquardt::Summary s = LevenbergMarquardt::solve(problem, o);
  ASSERT_FALSE(problem.accepted().empty());
  for (const Eigen::VectorXd& x : problem.accepted()) EXPECT_LT(x(0), 1.5);
  // The first step, 2 / (1 + lambda_0) from the damped system [1; sqrt(lambda_0)] dx =
  // [2; 0], ends outside and is halved once.
  EXPECT_NEAR(problem.accepted().front()(0), 0.5 * 2.0 / (1.0 + 1e-3), 1e-14);
  EXPECT_GT(problem.x()(0), 1.4);
  EXPECT_LT(problem.x()(0), 1.5);
  EXPECT_LT(s.final_cost, 0.5 * 0.6 * 0.6);
}

TEST(LevenbergMarquardtSolver, NoFeasibleStepFails) {
  // Every step from the boundary x = 1 towards the minimum at 2 leaves the domain
  // x <= 1 and the gradient is not small: the damping grows to its limit and the
  // run fails without moving.
  DenseProblem problem([](const Eigen::VectorXd& x) { return Eigen::VectorXd::Constant(4, x(0) - 2.0); },
                       [](const Eigen::VectorXd&) { return Eigen::MatrixXd::Ones(4, 1); }, Eigen::VectorXd::Ones(1),
                       [](const Eigen::VectorXd& x) { return x(0) <= 1.0; });
  LevenbergMarquardt::Options o;
  o.max_damping = 1e4;
  const LevenbergMarquardt::Summary s = LevenbergMarquardt::solve(problem, o);
  EXPECT_EQ(s.status, LevenbergMarquardt::Status::failed) << s.brief_report();
  EXPECT_NE(s.termination.find("damping limit"), std::string::npos) << s.termination;
  EXPECT_GT(s.damping, 1e4);
  EXPECT_TRUE(problem.accepted().empty());
  EXPECT_EQ(problem.x()(0), 1.0);
  EXPECT_EQ(s.final_cost, 2.0);
}

}  // namespace test_unit_core_levenberg_marquardt
