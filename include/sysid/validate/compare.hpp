#pragma once
/// @file
/// Purpose: compare a model with measured data: initial-state estimation, k-step
/// ahead prediction with the innovation-form (Kalman) predictor, and the fit %
/// of simulation or prediction (DESIGN.md "Fit and validation").
///
/// The model is the innovation form identified by the subspace methods
///
///   x[t+1] = A x[t] + B u[t] + K e[t],   y[t] = C x[t] + D u[t] + e[t],
///
/// whose one-step predictor is x^[t+1|t] = A x^[t|t-1] + B u[t] + K (y[t] - y^[t|t-1]),
/// y^[t|t-1] = C x^[t|t-1] + D u[t] (Ljung, System Identification: Theory for the
/// User, 2nd ed., sec. 4.3, eq. 4.86 with the innovation form 4.84).
///
/// Offsets: compare() takes the data in the units of the log and subtracts
/// CompareOptions::input_offset / output_offset itself (the means n4sid removed,
/// stored in the model file), and returns y_hat in the units of the log.
/// estimate_initial_state() and predict_k_step() work on offset-free data.
#include <sysid/core/io_data.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/validate/fit.hpp>

#include <Eigen/Dense>

namespace sysid {

/// Purpose: least-squares initial state x0 of a model for measured data, i.e. the
/// x0 minimising || y - simulate(u, x0) || over the first `max_samples` samples.
///
/// Method: the output is affine in x0, y[t] = y_0[t] + C A^t x0 with y_0 =
/// simulate(u, 0), so x0 solves the stacked regression
///   [C; C A; C A^2; ...] x0 = y - y_0        (N' l equations, N' = min(N, max_samples)),
/// by a complete orthogonal decomposition (rank-revealing QR) of the stacked
/// observability matrix, never by normal equations: for lightly damped modes the
/// columns of that matrix are long and nearly parallel, and squaring its condition
/// number would lose half the digits. The columns are equilibrated to unit norm
/// before the QR (it is then invariant to the scaling of the state basis).
///
/// Preconditions: sys discrete (Ts > 0); u is N x m, y is N x l with the same N >= 1;
/// max_samples >= 1 (std::invalid_argument otherwise).
/// Numerical aspects: O(N' l n^2) for the regression plus one simulation;
/// memory O(N' l n). A direction the data cannot see (unobservable, or decayed to
/// nothing within N' samples) gets the minimum-norm value 0 (rank tolerance of
/// Eigen's COD: about n eps relative to the largest column norm).
/// Example: `Eigen::VectorXd x0 = estimate_initial_state(model, u, y);`
Eigen::VectorXd estimate_initial_state(const StateSpace& sys, const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                                       Eigen::Index max_samples = 2000);

/// Purpose: k-step-ahead prediction y^[t|t-k] (N x l) of the innovation-form model:
/// the Kalman predictor runs on the measured y up to time t-k, then the model runs
/// open loop (no output feedback) over the k-1 remaining steps, with the measured
/// inputs. k = 1 is the one-step predictor (y - y^ is the innovation when the
/// model and x0 are the true ones); for t < k the prediction is the open-loop
/// simulation from x0, so k >= N equals simulate(u, x0).
///
/// Method: the filter states xf[s] = x^[s|s-1] (xf[0] = x0) come from one pass of
/// the predictor recursion (A - K C) x + (B - K D) u + K y. Then
///   x^[t|t-k] = A^(k-1) xf[t-k+1] + sum_{j=t-k+1}^{t-1} A^(t-1-j) B u[j].
/// For a stable A (spectral radius < 1) the sum is the difference of the zero-state
/// simulation z: sum = z[t] - A^(k-1) z[t-k+1], so
///   x^[t|t-k] = z[t] + A^(k-1) (xf[t-k+1] - z[t-k+1]),
/// two GEMMs over the record, O(N n^2) whatever k. For an unstable A, z grows
/// without bound while x^ follows the data, and the difference would cancel
/// catastrophically; there the k-1 open-loop steps are run explicitly from every
/// xf[t-k+1], O(N k n^2).
///
/// Preconditions: sys discrete; K is n x l; u is N x m, y is N x l; k >= 1; x0 empty
/// (zero) or of size n. Violations throw std::invalid_argument.
/// Numerical aspects: the filter recursion is stable when A - K C is (which the
/// steady-state Kalman gain guarantees for a detectable model).
Eigen::MatrixXd predict_k_step(const StateSpace& sys, const Eigen::MatrixXd& K, const Eigen::MatrixXd& u,
                               const Eigen::MatrixXd& y, int k, const Eigen::VectorXd& x0);

struct CompareOptions {
  /// 0 = simulation (the DESIGN.md fit); k >= 1 = k-step-ahead prediction (needs K).
  int predict_steps = 0;
  /// true: x0 by estimate_initial_state on this data; false: `x0` below (empty = zero).
  bool estimate_x0 = true;
  Eigen::VectorXd x0;
  /// Samples used by the x0 estimate (estimate_initial_state's max_samples).
  Eigen::Index x0_max_samples = 2000;
  /// Means removed before identification (model file input_offset / output_offset);
  /// empty = zero. compare() subtracts them from u and y and adds output_offset to y_hat.
  Eigen::VectorXd input_offset, output_offset;
};

struct CompareResult {
  Eigen::VectorXd fit_percent;  ///< per output, 100 (1 - ||y - y_hat|| / ||y - mean(y)||)
  Eigen::MatrixXd y_hat;        ///< N x l, in the units of the data (output offset added back)
  Eigen::VectorXd x0;           ///< initial state used
};

/// Purpose: fit of a model on one experiment, by simulation (predict_steps = 0) or
/// k-step prediction, with x0 estimated on the same data or given.
/// Method: offsets removed; x0 by estimate_initial_state (the simulation-error
/// optimal x0, also used to start the predictor); simulate or predict_k_step;
/// fit_percent.
/// Preconditions: sys discrete; data.u N x m, data.y N x l; K n x l when
/// predict_steps > 0 (std::invalid_argument "compare: k-step prediction needs the
/// Kalman gain K" when it is empty); offsets of size m, l or empty.
/// Example: `CompareResult r = compare(model, K, data.experiments[0], {.predict_steps = 1});`
CompareResult compare(const StateSpace& sys, const Eigen::MatrixXd& K, const Experiment& data, const CompareOptions& options = {});

/// Purpose: the fit over every experiment of a data set (each with its own x0),
/// pooled over the experiments as if concatenated (so a long record weighs more).
/// Preconditions: as compare(); options.estimate_x0 or one x0 for all experiments.
Eigen::VectorXd compare_fit(const StateSpace& sys, const Eigen::MatrixXd& K, const IoData& data,
                            const CompareOptions& options = {});

}  // namespace sysid
