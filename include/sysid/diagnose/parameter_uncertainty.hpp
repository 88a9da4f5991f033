#pragma once
/// @file
/// Purpose: standard errors of the physics parameters fitted by candidate_fit.hpp
/// (issue 33, item 4): every finding of `sysid diagnose` reports one per
/// parameter, and a finding whose defining parameter lies within two standard
/// errors of zero is dropped.
///
/// Method: the fit minimises sum_i s_i^2 ||y_i - yhat_i(theta)||^2 over rows
/// [0, rows), s_i = 1 / std(y_i) (simulation_cost's 1 / var(y_i) on the squared
/// errors). With the weighted residuals r_ti = s_i (y_ti - yhat_ti) and the
/// weighted Jacobian J_ti = s_i d yhat_ti / d theta (theta: the free parameters
/// in their own units), the Gauss-Newton (sandwich) covariance of the estimate is
///   Cov = (J'J)^-1  S  (J'J)^-1,
///   S = sum_i [ Gamma_0i + sum_{k=1..L} w_k (Gamma_ki + Gamma_ki') ],
///   Gamma_ki = sum_t g_ti g_(t+k)i',  g_ti = J_ti' r_ti,  w_k = 1 - k / (L + 1),
/// the heteroscedasticity and autocorrelation consistent estimate of Newey and
/// West, "A simple, positive semi-definite, heteroskedasticity and
/// autocorrelation consistent covariance matrix", Econometrica 55 (1987) 703-708,
/// eq. (2)-(3), applied to the nonlinear least-squares score as in their sec. 3:
/// a simulation error is coloured (the nominal's own errors, unmodelled
/// dynamics), and the white-noise formula sigma^2 (J'J)^-1 then understates the
/// spread. Each output's time series is summed separately and the sums added
/// (the outputs' errors taken as mutually uncorrelated, as in improvement_z of
/// diagnose.cpp). For one output the weight s_1 cancels: the standard errors
/// are in the parameters' own units and do not depend on the weighting.
/// L = min(max_correlation_lag, rows / 4), the acceptance test's window. L = 0
/// gives the white-noise (Eicker-White) sandwich. Because the scores sum to zero
/// at the optimum, the sample autocovariances are pulled down and E[S] is about
/// (1 - b + b^2/3) times the true S for b = L / rows (the mean of the Bartlett
/// kernel's fixed-b limit: Kiefer and Vogelsang, "A new asymptotic theory for
/// heteroskedasticity-autocorrelation robust tests", Econometric Theory 21 (2005)
/// 1130-1164); S is divided by that factor (up to 1.3 at L = rows / 4: without
/// it the standard errors came out about 10 % low in the Monte-Carlo tests).
///
/// J is taken by central differences in the fit coordinate z of candidate_fit
/// (unit box, logarithmic for log_scale): z +- relative_step, mapped to the
/// parameter's units, so the step is a fixed fraction of the box; one-sided at a
/// bound. (J'J)^-1 is never formed: J D^-1 (D = its column norms) is reduced by
/// Householder QR to R and R by an SVD, (J'J)^+ = D^-1 V Sigma^-2 V' D^-1.
///
/// Numerical aspects: at most 2p + 1 simulations (p free parameters; one fewer
/// for each at a bound) and O(rows l p^2 L) for S. A parameter whose step
/// changes the weighted simulation by less than 1e-10 of its norm has no effect;
/// a singular value of J D^-1 below rank_tolerance times the largest is a null
/// direction, and every parameter with a component above 1e-3 in the null space
/// (a parameter with no effect, two that act alike) is not identifiable: its
/// standard error is +inf and a warning names it; the others' are those of
/// estimable functions (pseudo-inverse). The formula assumes an interior optimum;
/// a parameter at a bound of its box gets a warning.
#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

#include "sysid/diagnose/augmented_model.hpp"
#include "sysid/diagnose/candidate_fit.hpp"
#include "sysid/diagnose/physics_block.hpp"

namespace sysid {

struct ParameterUncertaintyOptions {
  /// L requested: Bartlett window of the score autocovariance (>= 0; 0: white noise).
  /// The window used is min(L, rows / 4).
  Eigen::Index max_correlation_lag = 500;
  /// Finite-difference step in the unit-box coordinate: this fraction of the box
  /// width (of log(upper / lower) for log_scale). In (0, 0.25].
  double relative_step = 1e-3;
  /// A singular value of the column-scaled Jacobian below this times the largest
  /// is treated as zero (condition number above 1 / rank_tolerance: rank deficient). In (0, 1).
  double rank_tolerance = 1e-7;
};

struct ParameterUncertainty {
  /// Per candidate (in the order given), per free parameter name: the standard
  /// error in the parameter's units; +inf when not identifiable, 0 for a free
  /// parameter whose box is empty (lower == upper: held, not estimated).
  std::vector<std::map<std::string, double>> standard_errors;
  /// Covariance of all free parameters in `names` order (candidate by candidate,
  /// each in `free` order). A non-identifiable parameter has +inf on the diagonal
  /// and NaN elsewhere in its row and column (its correlations are undefined).
  Eigen::MatrixXd covariance;
  std::vector<std::string> names;   ///< "kind.param", the order of `covariance`
  std::vector<bool> identifiable;   ///< the same order
  double condition_number = 0.0;    ///< of J D^-1 (+inf when rank deficient; 0 when nothing is estimated)
  Eigen::Index rank = 0;            ///< numerical rank of J D^-1
  Eigen::Index correlation_lag = 0; ///< L used
  std::vector<std::string> warnings;
};

/// Standard errors of the free parameters of `fitted` (at their values in each
/// block), with `fixed` blocks held, on rows [0, rows) of (u, y) in deviation
/// coordinates — the data the fit saw (fit_candidates' arguments).
/// Preconditions (std::invalid_argument): u.cols() == simulator's inputs,
/// y.cols() == its outputs, p < rows <= u.rows() == y.rows() (p: free parameters in total),
/// u and y finite on those rows, every free name a parameter of its block's kind,
/// lower <= value <= upper (to 1e-9 of the box), log-scale bounds > 0, options in range.
ParameterUncertainty parameter_uncertainty(const AugmentedSimulator& simulator, const std::vector<PhysicsBlock>& fixed,
                                           const std::vector<Candidate>& fitted, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                           const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::Index rows,
                                           const ParameterUncertaintyOptions& options = {});

/// One candidate's share of a ParameterUncertainty: the covariance of its free
/// parameters (in `free` order) and their standard errors.
struct CandidateUncertainty {
  Eigen::MatrixXd covariance;
  std::map<std::string, double> standard_errors;
};

/// Candidate k's block of `u` (candidates in the order they were given).
CandidateUncertainty candidate_uncertainty(const ParameterUncertainty& u, const std::vector<Candidate>& fitted, std::size_t k);

/// How far a parameter is from the value at which its effect vanishes, in
/// standard errors: |value - null| / SE (for a `reciprocal` parameter, |1/value| /
/// (SE / value^2)); NaN when the parameter is not free (held: nothing to test).
double distance_from_null(const Candidate& c, const DefiningParameter& d, const std::map<std::string, double>& standard_errors);

/// DESIGN.md "diagnose": whether at least one of the kind's defining parameters
/// (BlockKindInfo::defining) differs from its null value by more than `z`
/// standard errors — the finding may then be reported under its kind's name. True
/// when none of them is free (nothing to test: a clipping level). `why` (when
/// given) gets the distances in words.
bool defining_parameter_differs(const Candidate& c, const std::map<std::string, double>& standard_errors, double z,
                                std::string* why = nullptr);

/// The kind's optional terms (BlockKindInfo::optional_terms) that are free but
/// within `z` standard errors of their null value: the data do not show them.
std::vector<DefiningParameter> insignificant_optional_terms(const Candidate& c,
                                                            const std::map<std::string, double>& standard_errors, double z);

/// Holds the given optional terms at their null values: set, and no longer free.
void hold_at_null(Candidate& c, const std::vector<DefiningParameter>& terms);

}  // namespace sysid
