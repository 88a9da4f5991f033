#pragma once
/// @file
/// Purpose: the uncertainty weight of a model family: a low-order, stable,
/// minimum-phase, single-input single-output discrete-time filter W whose gain
/// covers a bound at every listed frequency, |W(e^{j 2 pi f_k Ts})| >= bound_k: the
/// weight of P = (I + W Delta) P_0, ||Delta||_inf <= 1, that H-infinity and mu
/// design take (Skogestad and Postlethwaite, Multivariable Feedback Control, 2nd
/// ed., 2005, sec. 7.4; what MATLAB's ucover / fitmagfrd return). DESIGN.md,
/// "Model families over operating conditions", `uncertainty.weight`.
///
/// Method:
///  1. Parametrisation (every pole and zero strictly inside the circle of radius
///     r_max = max_radius, for every parameter value):
///       W(z) = g prod_i N_i(z) / D_i(z)  [* (z - z_0) / (z - p_0) for odd order],
///     g = exp(x_0); each N_i, D_i is a monic quadratic z^2 + a_1 z + a_2 whose
///     roots are exp(lambda - delta), delta = -log(r_max), lambda the roots of
///     lambda^2 + q_1 lambda + q_0 with q_1 = exp(alpha) > 0, q_0 = exp(beta) > 0
///     (a Hurwitz quadratic in the normalised Laplace variable s Ts, i.e. the
///     pole-zero mapping z = exp(s Ts) of a second-order factor with damping
///     zeta = q_1 / (2 sqrt(q_0)) and natural frequency sqrt(q_0) / Ts; zeta > 1
///     gives two positive real roots). In closed form
///       a_2 = exp(-2 delta - q_1),  a_1 = -2 exp(-delta - q_1 / 2) cos(sqrt(q_0 - q_1^2 / 4)),
///     with cos(sqrt(x)) continued by cosh(sqrt(-x)) for x < 0 (an entire function
///     of x, so the map is smooth through critical damping). First-order roots are
///     exp(-delta - exp(gamma)). Log-parameters put light damping, low corner
///     frequencies and gains on the scale the fit needs.
///  2. Fit of e_k(x) = log|W(e^{j theta_k})| - log bound_k (theta_k = 2 pi f_k Ts;
///     points with bound_k = 0 take no part): Levenberg-Marquardt
///     (core/levenberg_marquardt.hpp; analytic Jacobian, d log|P| / d a_1 =
///     Re(z / P), d log|P| / d a_2 = Re(1 / P)) on the asymmetric residuals
///     r_k = e_k (e_k >= 0), below_penalty * e_k (e_k < 0), from several starts:
///     - a linear fit: |W|^2 = P_N(c) / P_D(c), c = cos theta, P_N, P_D of degree
///       `order` in c (Chebyshev basis over the grid's range of c), by
///       Sanathanan-Koerner iterations (C. K. Sanathanan, J. Koerner, IEEE Trans.
///       Autom. Control 8 (1963) 56-58), each the total least-squares solution of
///       P_N(c_k) - bound_k^2 P_D(c_k) ~ 0 weighted by 1 / sqrt|bound_k^2 P_N P_D|
///       of the previous iterate (residual rho - 1/rho in rho = |W| / bound); each
///       root c_r of P_N (P_D) gives the zero (pole) a, z + 1/z = 2 c_r, |a| <= 1
///       (the spectral factor). Exact when the bound is the gain of such a filter;
///     - features of the bound: the log bound minus its running median over
///       +-half an octave; its peaks (resonances) and valleys (anti-resonances)
///       with their heights h and relative half-widths eps (at half the log
///       height). A peak becomes a section with poles at its frequency and
///       damping zeta_p = eps / sqrt(H) and zeros there with zeta_z = eps sqrt(H),
///       H = exp(h) (the peak of (s^2 + 2 zeta_z w s + w^2) / (s^2 + 2 zeta_p w s + w^2)
///       is zeta_z / zeta_p = H and its log falls to half at relative detuning
///       zeta_p sqrt(H)); a valley the same with poles and zeros swapped. Starts
///       with the k highest peaks (k = 0 .. order/2), with the k most prominent
///       features, and with each of the next peaks alone, the other sections
///       smooth (well-damped zeros and poles spread over the band);
///     - continuation over the order: orders 1, 2, ..., `order` are fitted in
///       turn, each also from the best fit of the order below extended by a
///       neutral root (zero = pole; also kept as a candidate as it is, so a
///       higher order does not fit worse, but for roots clamped at the radius
///       limit) and from the best fit two orders below
///       with a section added at the largest feature of its residual (greedy).
///     Each fit is shifted to cover (x_0 -= min_k e_k) and scored by its mean log
///     conservatism mean_k e_k (the log of the geometric-mean |W| / bound).
///  3. Refinement of the best `refine_starts` fits of each order: the constrained
///     problem
///       minimise mean_k e_k(x)  subject to  e_k(x) >= 0 for every k
///     (the L1 fit of the log bound from above, as fitmagfrd's fit from above: it
///     makes many points tight, so the median conservatism small), by sequential
///     quadratic programming (D. Kraft, "A software package for sequential
///     quadratic programming", DFVLR-FB 88-28, 1988; NLopt's LD_SLSQP) started
///     from the covering fit; the best covering score evaluated is kept. Grids of
///     more than 600 points constrain a working set (local minima of e and the
///     smallest e_k), grown by the points a round leaves below the bound.
///  4. The best fit is realised as a cascade of sections (series connection, each
///     N_i / D_i = 1 + (c_1 z + c_0) / D_i(z)) in the real form
///     A_i = [re, kappa; -s / kappa, re] (re = -a_1 / 2, s = a_2 - a_1^2 / 4,
///     kappa = max(sqrt|s|, 1e-3): a normal matrix for distinct roots, tending to a
///     Jordan block for a double root), B_i and C_i scaled to one norm; never the
///     expanded high-order polynomial. Its gain is finally set from |W| evaluated
///     on the realisation (core/frequency_response.hpp):
///     g *= (1 + 1e-12) max_k bound_k / |W_k|, so the cover holds at every grid
///     point by construction (min_ratio >= 1), the 1e-12 a margin for rounding in
///     another evaluation of |W|.
///  5. Warnings: points with bound 0; fewer points than parameters; a median
///     conservatism above 2; a root at the radius limit; |W| off the grid (a
///     dense check over [0, Nyquist) and the band) above twice its largest value
///     on the grid.
///
/// Preconditions (std::invalid_argument otherwise): Ts > 0 and finite;
/// frequency_hz and bound of one size >= 1; frequencies finite, strictly
/// increasing, 0 <= f < 0.5 / Ts; bounds finite, >= 0, not all zero;
/// 1 <= order <= 6; 0 < max_radius < 1; below_penalty >= 1; starts >= 1;
/// max_iterations >= 1; refine_starts >= 0.
///
/// Numerical aspects: per LM iteration O(N order^2) for the Jacobian's QR (N grid
/// points); per order up to `starts` + 2 fits of at most `max_iterations`
/// iterations, plus `refine_starts` SQP runs of at most `refine_evaluations`
/// evaluations, each O(N order) plus the QP over at most ~N constraints. Measured
/// (clang -O2, one core): 400 points, order 6, 0.05-0.15 s; 5000 points, order 6,
/// about 1 s. Deterministic (no random starts). The cover is exact only at the
/// listed frequencies: between grid points a bound narrower than the grid spacing
/// can exceed |W|. The fit is a local search: a better weight of the same order
/// may exist, most likely when the bound has more peaks than order / 2.
///
/// References: Skogestad & Postlethwaite (2005), sec. 7.4.3 (weights from a set
/// of plants); G. Balas et al., Robust Control Toolbox, `ucover`, `fitmagfrd`
/// (magnitude fit from above); K. Levenberg 1944, D. W. Marquardt 1963; D. Kraft
/// 1988 (SLSQP).
///
/// Example:
///   UncertaintyWeightOptions o;  o.order = 4;
///   const UncertaintyWeightResult w = fit_uncertainty_weight(f_hz, bound, 5e-4, o);
///   // w.weight: SISO StateSpace at Ts = 5e-4, |W| >= bound on f_hz
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

struct UncertaintyWeightOptions {
  int order = 4;  ///< number of poles (= zeros) of W, 1..6
  /// Largest radius of a pole or zero of W (each is strictly inside the circle of
  /// this radius by construction): 1 - max_radius is the lightest relative damping
  /// zeta w Ts a resonance of W can have.
  double max_radius = 0.9999;
  /// Weight of the log-residuals below the bound in the Levenberg-Marquardt fits
  /// (those above weigh 1): the larger, the closer each fit is to a cover.
  double below_penalty = 10.0;
  /// Most independent starting points of the Levenberg-Marquardt stage per order
  /// (the linear fit and the feature starts; the two extensions of the lower
  /// orders' fits come on top; duplicates are not run twice).
  int starts = 12;
  /// Iteration budget of each Levenberg-Marquardt fit.
  int max_iterations = 150;
  /// How many of the best covering fits of each order the constrained SQP
  /// refinement (step 3 of the file comment) starts from; 0 skips the refinement.
  int refine_starts = 2;
  /// Evaluation budget of each SQP refinement (0 skips the refinement).
  int refine_evaluations = 300;
};

struct UncertaintyWeightResult {
  /// SISO, discrete at the given Ts, stable and minimum-phase (all poles and zeros
  /// strictly inside the unit circle, indeed inside max_radius).
  StateSpace weight;
  Eigen::VectorXd magnitude;  ///< |W| at each frequency of the grid (evaluated on `weight`)
  /// Median over the grid of |W| / bound (points with bound > 0 only).
  double median_conservatism = 0.0;
  double max_conservatism = 0.0;  ///< max over the grid of |W| / bound (bound > 0)
  double max_conservatism_hz = 0.0;  ///< frequency of max_conservatism
  /// min over the grid of |W| / bound (bound > 0): >= 1 by construction (the cover
  /// is guaranteed at every listed frequency).
  double min_ratio = 0.0;
  /// Levenberg-Marquardt iterations over all starts and orders plus SQP evaluations.
  int iterations = 0;
  int starts = 0;  ///< Levenberg-Marquardt fits run, over all orders
  std::vector<std::string> warnings;

  /// One line: order, median / max conservatism and where, iterations.
  std::string brief_report() const;
};

/// Purpose: fit the uncertainty weight, see the file comment.
/// frequency_hz: the grid (Hz, strictly increasing, 0 <= f < 0.5 / Ts); bound: the
/// magnitude to cover at each of its points (>= 0; 0 = no requirement there).
UncertaintyWeightResult fit_uncertainty_weight(const Eigen::VectorXd& frequency_hz, const Eigen::VectorXd& bound,
                                               double Ts, const UncertaintyWeightOptions& options = {});

}  // namespace sysid
