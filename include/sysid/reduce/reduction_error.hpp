#pragma once
/// @file
/// Purpose: the one piece of code that measures how far a reduced model is from
/// the full one, ||G - G_r||_inf = sup_f sigma_max(G(f) - G_r(f)), and the Result
/// type every reduction method returns (ReductionResult), so balanced truncation,
/// singular perturbation and modal truncation report their errors the same way.
///
/// Method: sigma_max of the difference of the two frequency responses
/// (core/frequency_response.hpp, Laub 1981) on a dense grid:
///  - log-spaced: `log_points` points from f_lo to f_hi, plus f = 0 and f_hi.
///    Discrete: f_hi = Nyquist 1/(2 Ts); continuous: f_hi = 10 x the largest natural
///    frequency of any pole (and sigma_max(D - D_r), the value at infinity).
///    f_lo = 10^-decades_below x the smallest positive natural frequency.
///  - refined at every complex pole of either model: with s the continuous-time
///    equivalent of the pole (log(z)/Ts if discrete), a resonance peaks near
///    f_p = |Im s|/(2 pi) with half-power half-width w = |Re s|/(2 pi); the points
///    f_p + w {0, +-1/8, +-1/4, +-1/2, +-1, +-2, +-4} are added.
/// The grid maximum is a lower estimate of the true norm. Where the peak is one
/// resonance, |G| ~ 1/|j(f - f_p) + w| near it and the largest distance to a grid
/// point within +-w/4 is w/16, so the estimate is low by at most
/// 1 - 1/sqrt(1 + 1/16^2) ~ 0.2 %; elsewhere the log spacing (e.g. 400 points over
/// 6 decades: ratio 1.035) resolves a response that varies on the scale of the
/// poles' own half-widths, which the refinement covers.
///
/// Preconditions: both models valid, same Ts and the same numbers of inputs and
/// outputs (std::invalid_argument otherwise).
/// Numerical aspects: O(n^3) once plus O(n^2 m) per grid point for each model;
/// sigma_max from the eigenvalues of the smaller Gram matrix of each l x m
/// difference (absolute accuracy eps sigma_max^2 in sigma_max^2, plenty for the
/// largest singular value). A pole exactly on the grid gives an infinite error.
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

namespace sysid {

struct ErrorGridOptions {
  int log_points = 400;        ///< log-spaced points between f_lo and f_hi (>= 2)
  double decades_below = 3.0;  ///< f_lo = 10^-decades_below x the smallest positive pole frequency (> 0)
};

/// Peak of sigma_max(G - G_r) over the grid.
struct HinfErrorEstimate {
  double value = 0.0;    ///< max over the grid (a lower estimate of the H-infinity norm)
  double freq_hz = 0.0;  ///< where it occurs (Inf: at infinite frequency, continuous only)
  double dc = 0.0;       ///< sigma_max at f = 0 (the static gain error)
  Eigen::Index grid_points = 0;
};

/// The Result every reduction method returns (balanced_truncation.hpp,
/// modal_truncation.hpp). Fields that a method does not produce stay NaN/empty.
struct ReductionResult {
  StateSpace model;            ///< the reduced model (same Ts, inputs, outputs, names)
  std::string method;          ///< "balanced truncation", "singular perturbation", "modal truncation"
  Eigen::Index original_order = 0;
  Eigen::Index order = 0;            ///< order of `model`
  Eigen::Index unstable_states = 0;  ///< states of the unstable part, kept whole
  Eigen::VectorXd hsv;               ///< Hankel singular values of the stable part, descending (balanced methods)
  /// (sum of all HSV - sum of kept HSV) / sum of all HSV (the isolator paper's ratio).
  double error_ratio = std::numeric_limits<double>::quiet_NaN();
  /// 2 x sum of the discarded HSV: ||G - G_r||_inf <= hinf_bound (balanced methods).
  double hinf_bound = std::numeric_limits<double>::quiet_NaN();
  /// ||G - G_r||_inf measured on the grid (reduction_error.hpp), NaN if not measured.
  double hinf_error = std::numeric_limits<double>::quiet_NaN();
  double hinf_error_freq_hz = std::numeric_limits<double>::quiet_NaN();
  double dc_error = std::numeric_limits<double>::quiet_NaN();  ///< sigma_max(G(0) - G_r(0))
  Eigen::Index grid_points = 0;
  std::vector<Mode> kept_modes, removed_modes;  ///< modal truncation only
  std::vector<std::string> warnings;

  /// One line per figure, for logs and the CLI.
  std::string brief_report() const;
};

/// Purpose: the frequency grid described in the file comment, for a set of poles
/// (z if Ts > 0, s if Ts = 0). Sorted ascending, without duplicates, starting at 0.
/// Preconditions: Ts >= 0; options.log_points >= 2, options.decades_below > 0.
Eigen::VectorXd error_frequency_grid(const Eigen::VectorXcd& poles, double Ts,
                                     const ErrorGridOptions& options = {});

/// Purpose: ||G - G_r||_inf estimated on the grid of the file comment, built from
/// the poles of both models.
/// Preconditions: see the file comment.
HinfErrorEstimate reduction_error(const StateSpace& full, const StateSpace& reduced,
                                  const ErrorGridOptions& options = {});

/// Purpose: ||E||_inf of an error system E = G - G_r given as one model (e.g. the
/// removed modes of a modal truncation), on the grid of its own poles.
HinfErrorEstimate hinf_norm_estimate(const StateSpace& error_system, const ErrorGridOptions& options = {});

}  // namespace sysid
