#pragma once
/// @file
/// Purpose: a Levenberg-Marquardt solver for nonlinear least squares
///   minimise F(x) = 1/2 ||r(x)||^2,   r: R^n -> R^N,
/// small enough to read in one sitting and reusable by any residual (after Ceres'
/// `tiny_solver.h`): the caller describes its residual through the
/// LevenbergMarquardt::Problem interface, the solver owns the damping, the steps
/// and the stopping rules. It can be run to the end (`solve`) or one iteration at
/// a time (`iterate`, `iterate_up_to`, `ended`), so that several starts of one
/// problem can be raced in step and the best continued (pem's automatic ARMAX
/// start, pem/prediction_error.hpp).
///
/// Method (K. Levenberg, Quart. Appl. Math. 2 (1944) 164-168; D. W. Marquardt,
/// J. SIAM 11 (1963) 431-441; H. B. Nielsen, "Damping parameter in Marquardt's
/// method", IMM-REP-1999-05, DTU, 1999):
/// - the problem supplies R, the (n+1) x (n+1) upper-triangular factor of [J r]
///   (J = dr/dx at x): with R = [R11 r12; 0 rho], J^T J = R11^T R11, J^T r =
///   R11^T r12 and ||r||^2 = ||r12||^2 + rho^2. The factor may come from a QR of
///   [J r] or a Cholesky factor of its Gram matrix; the solver never sees J;
/// - the step dx minimises ||R11 dx + r12||^2 + lambda ||D dx||^2 with Marquardt's
///   scaling D = diag(column norms of J) = diag(column norms of R11) (each floored
///   at 1e-12 max(1, max D) so a zero column stays damped), solved by a Householder
///   QR of [R11; sqrt(lambda) D] (never the normal equations: their condition is
///   the square of J's);
/// - a step whose end leaves the problem's domain (Problem::set_candidate returns
///   false: for pem, an unstable predictor) is halved, at most until its fraction
///   is below 0.1, before the cost is evaluated; the quadratic model stays right,
///   only the constraint bites, so this is cheaper than raising the damping;
/// - gain ratio rho = (F(x) - F(x + dx)) / (L(0) - L(dx)), L the Gauss-Newton
///   model, L(0) - L(dx) = 1/2 (||r12||^2 - ||R11 dx + r12||^2). A step is taken
///   when rho > 0. Damping after an accepted step: Nielsen's factor
///   max(1/3, 1 - (2 rho - 1)^3), except that a well-predicted step (rho > 0.75)
///   shrinks lambda by `shrink`, which starts at 0.1 and falls tenfold after each
///   further well-predicted step taken at the first try (0.1, 0.01, 1e-3, then 1e-4
///   each: the damping that suits an ill-conditioned problem can lie ten decades
///   below the start), and a step shortened by the domain leaves lambda alone.
///   After a rejected step lambda *= nu, nu *= 2 (nu = 2 after every accepted one);
/// - optional variable projection (G. H. Golub & V. Pereyra, SIAM J. Numer. Anal.
///   10 (1973) 413-432): when the problem eliminates a linear part of x (for
///   ARMAX: A and B by least squares for the current C), the solver lets it do so
///   at the start and after every accepted step, on top of the damped step, and
///   takes the step as the difference of the parameter vectors.
///
/// Stopping rules (Options; sigma^2 = 2 F(x) / max(1, N - n), the residual
/// variance; each rule sets status `converged` with its reason in `termination`):
/// - gradient: max_k |(J^T r)_k| <= gradient_tolerance (1 + F(x));
/// - step significance: ||r12||^2 <= step_significance_tolerance^2 sigma^2, i.e.
///   the full Gauss-Newton step -R11^-1 r12 is shorter than
///   step_significance_tolerance standard deviations of the estimate in the metric
///   of its covariance sigma^2 (J^T J)^-1 (Ljung, System Identification, 2nd ed.,
///   1999, eq. 9.17): further steps change nothing the data can distinguish;
/// - after a step accepted at the first try whose predicted decrease is at least
///   1/4 ||r12||^2 (so close to the Gauss-Newton step, not short because of the
///   damping): relative decrease F(x) - F(x + dx) <= function_tolerance F(x), or
///   step length ||dx|| <= parameter_tolerance (||x|| + parameter_tolerance);
/// - working precision: after rejections, a step that gains at most 1e-3 sigma^2
///   or moves x by rounding only (||dx|| <= 1e-9 (||x|| + 1e-9)), or no step at all
///   below lambda = max_damping, while the Gauss-Newton minimiser lies inside the
///   parameters' confidence region ||r12||^2 <= n sigma^2 (the mean of the
///   chi-square(n) that bounds it), or (no step at all) the gradient is below
///   1e-6 (1 + F(x)): rounding in an ill-conditioned or over-parametrised Jacobian
///   then hides a decrease the data cannot resolve.
/// No step below lambda = max_damping otherwise: status `failed`. The iteration
/// budget spent: status `max_iterations`.
///
/// Preconditions: parameter_count() >= 1; the factor is (n+1) x (n+1); options as
/// documented on each field (not checked: the solver only compares against them).
///
/// Numerical aspects: per iteration one factor of [J r] (the problem's cost, usually
/// O(N n^2) or less) and per trial step one QR of a 2n x n matrix (O(n^3)) and one
/// cost evaluation; memory O(n^2) in the solver.
///
/// Example:
///   struct Fit : LevenbergMarquardt::Problem { ... };   // residual, factor, candidate
///   Fit fit(data, x0);
///   const LevenbergMarquardt::Summary s = LevenbergMarquardt::solve(fit);
///   if (s.status != LevenbergMarquardt::Status::failed) use(fit);   // the problem holds x
#include <Eigen/Dense>

#include <string>
#include <vector>

namespace sysid {

class LevenbergMarquardt {
 public:
  struct Options {
    /// The iteration budget of solve() and the count named in the `max_iterations`
    /// status's message (iterate_up_to takes its own limit).
    int max_iterations = 100;
    /// Converged when max_k |(J^T r)_k| <= gradient_tolerance * (1 + F(x)).
    double gradient_tolerance = 1e-10;
    /// Converged when ||r12|| <= step_significance_tolerance * sigma, sigma^2 =
    /// 2 F(x) / max(1, N - n): the Gauss-Newton step is shorter than this many
    /// standard deviations of the estimate (Mahalanobis length). 0 disables the test.
    double step_significance_tolerance = 0.1;
    /// Converged when a near-Gauss-Newton step lowers F by at most
    /// function_tolerance * F(x): F(x) - F(x + dx) <= function_tolerance * F(x).
    double function_tolerance = 1e-10;
    /// Converged when a near-Gauss-Newton step has
    /// ||dx|| <= parameter_tolerance * (||x|| + parameter_tolerance). 0 disables the test.
    double parameter_tolerance = 0;
    /// lambda at the start (in units of the scaled problem: D^T D lambda against J^T J).
    double initial_damping = 1e-3;
    /// The damping is not raised past this: no acceptable step below it ends the run.
    double max_damping = 1e16;
  };

  enum class Status {
    converged,       ///< a stopping rule of the file comment met (`termination` says which)
    max_iterations,  ///< the iteration budget spent first
    failed           ///< no step lowers the cost although the gradient is not small
  };

  struct Summary {
    Status status = Status::failed;
    std::string termination;  ///< which criterion ended the iterations, in words
    int iterations = 0;       ///< iterations that computed a step (accepted or not)
    double initial_cost = 0;  ///< F at the start, before any elimination
    double final_cost = 0;    ///< F at the end
    /// F at the start, after the start's elimination when that lowered it, then after
    /// every accepted step.
    std::vector<double> cost_history;
    /// R factor of [J r] at the final point ((n+1) x (n+1), upper triangular): the
    /// caller's covariance sigma^2 (R11^T R11)^-1 and conditioning come from it.
    Eigen::MatrixXd r;
    double damping = 1e-3;  ///< lambda at the end

    /// One line: status, reason, iterations, initial and final cost.
    std::string brief_report() const;
  };

  /// The residual r(x) the solver minimises, seen at two points: the current one
  /// (where the solver stands) and a candidate (the end of a trial step). The
  /// problem owns both; the solver keeps its own copy of x, so a problem may hold
  /// its parameters in any form (pem holds a polynomial model).
  class Problem {
   public:
    virtual ~Problem() = default;
    /// N, the number of residuals (for sigma^2 = 2 F / max(1, N - n)).
    virtual Eigen::Index residual_count() const = 0;
    /// n, the number of parameters.
    virtual Eigen::Index parameter_count() const = 0;
    /// x at the current point.
    virtual Eigen::VectorXd parameters() const = 0;
    /// F = 1/2 ||r||^2 at the current point; called once, when the solver starts.
    virtual double cost() = 0;
    /// The (n+1) x (n+1) upper-triangular R factor of [J r] at the current point.
    virtual Eigen::MatrixXd jacobian_factor() = 0;
    /// Makes x the candidate; false when x lies outside the problem's domain (the
    /// solver then shortens the step and tries again).
    virtual bool set_candidate(const Eigen::VectorXd& x) = 0;
    /// F at the candidate (only called after set_candidate returned true).
    virtual double candidate_cost() = 0;
    /// The candidate becomes the current point.
    virtual void accept_candidate() = 0;

    /// Variable projection: whether the problem eliminates a linear part of x.
    virtual bool eliminates_linear_part() const { return false; }
    /// The linear part re-solved at the current point (at the start), whose cost is
    /// `cost`; returns the cost afterwards (never above `cost`).
    virtual double eliminate_linear_part(double cost) { return cost; }
    /// The same at the candidate of an accepted step.
    virtual double eliminate_linear_part_of_candidate(double cost) { return cost; }
    /// x at the candidate (read after eliminate_linear_part_of_candidate).
    virtual Eigen::VectorXd candidate_parameters() const { return Eigen::VectorXd(); }
  };

  /// Starts a run at the problem's current point: evaluates F, eliminates the linear
  /// part when the problem has one, and factors [J r]. `problem` must outlive the
  /// solver (it is held by reference). (Overloads rather than `= {}`: a nested
  /// struct's default member initializers are not usable inside its own class.)
  LevenbergMarquardt(Problem& problem, const Options& options);
  explicit LevenbergMarquardt(Problem& problem);

  /// One iteration (its first checks may find convergence without a step): false
  /// once the run has ended, converged or failed (then status() says why).
  bool iterate();
  /// Iterates until the run ends or has taken `max_iterations` iterations in all
  /// (counted from the start of the run, so it resumes where an earlier call stopped).
  void iterate_up_to(int max_iterations);

  bool ended() const { return m_ended; }
  bool converged() const { return m_summary.status == Status::converged; }
  Status status() const { return m_summary.status; }
  int iterations() const { return m_iteration; }
  /// F at the current point.
  double current_cost() const { return m_cost; }

  /// The run as it stands: iterations, final cost and the factor at the final point
  /// (computed here when the last step moved the point). The run can go on after.
  Summary finish();

  /// A whole run: construct, iterate_up_to(options.max_iterations), finish.
  static Summary solve(Problem& problem, const Options& options);
  static Summary solve(Problem& problem);

 private:
  bool end();

  Problem& m_problem;
  Options m_options;
  Eigen::Index m_n = 0;
  Eigen::Index m_residuals = 0;
  Summary m_summary;
  double m_cost = 0;
  bool m_eliminate = false;
  Eigen::VectorXd m_x;
  double m_nu = 2.0;
  double m_shrink = 0.1;  // damping factor after a well-predicted step (file comment)
  int m_iteration = 0;
  bool m_need_factor = false;
  bool m_ended = false;
};

}  // namespace sysid
