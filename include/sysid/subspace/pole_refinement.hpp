#pragma once
/// @file
/// Purpose: re-estimate the poles of a subspace model by minimising its
/// simulation error on the estimation data, the model's output and mode shapes
/// (A's eigenvalues, C) starting where the subspace step left them. A subspace
/// model is one data compression's answer: its poles depend on the horizon, and
/// the directions the weighted projection leaves near its noise floor (a heavily
/// damped mode at the edge of a band-limited excitation, on the Par2 chirp at a
/// long horizon) come out wherever the noise puts them — a validation fit of 82 %
/// at one horizon and 99 % at the next. The simulation error does not depend on
/// the horizon, so its minimum makes the result independent of it (the
/// subspace-then-prediction-error practice of L. Ljung, System Identification,
/// 2nd ed., 1999, sec. 10.6 and MATLAB's ssest, here for the output-error
/// criterion).
///
/// Method: variable projection (G. H. Golub & V. Pereyra, SIAM J. Numer. Anal. 10
/// (1973) 413-432). A is put in real modal form T^-1 A T = blockdiag([lambda] or
/// [[Re, Im], [-Im, Re]]) (core/real_modal_form.hpp); the parameters are the
/// eigenvalues (Re and Im of each pair, each real eigenvalue), C T is held; for
/// given eigenvalues B, D and every experiment's x0 are the least-squares
/// solution of the simulation error (subspace/bdx_least_squares.hpp), and the
/// residual is that simulation error, each output divided by its RMS. The
/// Levenberg-Marquardt solver (core/levenberg_marquardt.hpp) minimises it with
/// a forward-difference Jacobian of the projected residual; a step that would
/// put a pole on or outside the unit circle is shortened. The simulation error
/// has local minima (on the Par2 chirp, the start from horizon 60's subspace
/// poles ends at 98.96 % with a pole at Nyquist, the start from horizon 20's at
/// 99.003 %, the true model's poles): several starts (subspace models of one
/// order from different horizons) are raced race_iterations iterations in step
/// and the one at the lowest cost goes on (as pem races its ARMAX starts). The
/// refined A is returned in its start's coordinates (T A_m T^-1), with that
/// start's C.
///
/// Cost: per iteration one B/D/x0 regression and simulation per eigenvalue
/// parameter (n of them), O(n N l (n m + l m + n)^2) in all; callers bound it
/// (refinement_cost below).
///
/// Preconditions (std::invalid_argument): at least one start; each A square n x n
/// with n >= 1, C l x n, data's outputs l; each A stable (spectral radius < 1).
#include <sysid/core/io_data.hpp>

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

struct PoleRefinementOptions {
  /// Levenberg-Marquardt iterations at most.
  int max_iterations = 30;
  /// Iterations every start runs before the lowest-cost one is continued alone.
  int race_iterations = 4;
  /// Per experiment, the first max_samples samples (as bdx_least_squares).
  Eigen::Index max_samples = 50000;
  /// Largest cond(T) of A's real modal form the refinement works in: beyond it
  /// the eigenvalues are ill-determined functions of A (near-defective) and the
  /// model is returned unrefined.
  double modal_condition_limit = 1e6;
};

/// A subspace model's A and C (the start of a refinement).
struct PoleRefinementStart {
  Eigen::MatrixXd A, C;
};

struct PoleRefinementResult {
  Eigen::MatrixXd A, C;       ///< refined A (or the start's, when not refined) and the start's C, in its coordinates
  std::size_t start = 0;      ///< the start the result came from
  bool refined = false;       ///< A changed: the refinement lowered the simulation error
  double initial_fit = 0;     ///< mean simulation fit % over the outputs, B, D, x0 by least squares, before
  double final_fit = 0;       ///< the same after
  int iterations = 0;
  std::string termination;    ///< the solver's reason, or why nothing was refined
};

/// The refined model's poles from the best of `starts` (see the file comment).
/// Starts without a well-conditioned real modal form, or whose regression breaks
/// down, are left out; when none remains the first start is returned unrefined.
PoleRefinementResult refine_poles(const std::vector<PoleRefinementStart>& starts, const IoData& data,
                                  const PoleRefinementOptions& options = {});

/// Floating-point operations of one Jacobian of refine_poles (n regressions of
/// N l rows and n m + l m + n columns, N = the samples used): what a caller
/// compares with its budget before refining.
double refinement_cost(Eigen::Index order, const IoData& data, Eigen::Index max_samples);

}  // namespace sysid
