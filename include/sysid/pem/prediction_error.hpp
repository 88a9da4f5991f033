#pragma once
/// @file
/// Purpose: prediction-error identification of ARMA, ARMAX and OE models (and
/// any structure of pem/polynomial_model.hpp with nonlinear parameters),
/// single output, any number of inputs (MISO):
///
///   minimise V(theta) = 1/2 sum_t eps(t, theta)^2,
///   eps = D/C (A y - sum_i B_i/F_i u_i(t - nk_i))   (Ljung 1999, eq. 4.33, 7.12).
///
/// Method:
///  - Levenberg-Marquardt (core/levenberg_marquardt.hpp, with the prediction-error
///    cost as its Problem) on the Gauss-Newton model of V (J. J. Moré, "The
///    Levenberg-Marquardt algorithm: implementation and theory", LNM 630, 1978;
///    the accept/reject and damping update of Nielsen 1999 as in Ceres'
///    tiny_solver). The Jacobian is analytic: filtered regressors (Ljung 1999,
///    sec. 10.3, eqs. 10.51-10.55):
///      d eps / d a_k  =  D/C          y(t-k)
///      d eps / d b_ik = -D/(C F_i)    u_i(t-nk_i-k)
///      d eps / d f_ik =  D/(C F_i)    w_i(t-k),  w_i = B_i/F_i u_i(t-nk_i)
///      d eps / d c_k  = -1/C          eps(t-k)
///      d eps / d d_k  =  1/C          v(t-k),    v = A y - sum_i w_i
///    all filtered from rest over each experiment. Each column is a shifted
///    copy of one of these few filtered signals, so the rows of [J eps] are
///    made chunk by chunk from them and streamed through a Householder QR
///    (core/streaming_qr.hpp): each iteration costs O(N p^2) time and
///    O(p^2 + N) memory (the N x p Jacobian is never held); the damped steps for
///    several lambda reuse the triangular factor.
///  - Denominators C, D, F_i are kept strictly stable (roots of the polynomial in
///    z inside the unit circle): a step that leaves the stable region is
///    first shortened along its direction (halved up to four times: the
///    quadratic model is still right, only the constraint bites), and rejected
///    with the damping increased when that does not help or the cost rises.
///    Consecutive well-predicted steps (gain ratio > 0.75 at the first try)
///    shrink the damping by 0.1, 0.01, 1e-3, then 1e-4 each: on the Par2 ARMAX the
///    damping that suits the problem lies 15 decades below the start.
///  - Variable projection for ARMA and ARMAX (no D, no F): once C is fixed,
///    eps = A (y / C) - sum_i B_i (u_i / C) is linear in the A and B
///    coefficients, so their best values for that C are an ARX least-squares
///    problem on the data filtered by 1 / C (G. H. Golub & V. Pereyra, SIAM J.
///    Numer. Anal. 10 (1973) 413-432; "Separable nonlinear least squares: the
///    variable projection method and its applications", Inverse Problems 19
///    (2003) R1-R26). It is solved at each start and after each accepted step
///    (the joint Levenberg-Marquardt step moves C, the projection puts A and B
///    at their optimum for it; the damping follows the joint step's gain ratio),
///    and kept only when it lowers the cost. The joint step taken from a point
///    where A and B are optimal is Kaufman's variable-projection step for C
///    (L. Kaufman, BIT 15 (1975) 49-57). On the Par2 ARMAX(32,32,26,0) the
///    subspace start's cost falls from 2.93 to 1.9879 by the projection alone
///    (the flat minimum lies at 1.984-1.988 whichever way it is approached) and
///    the Hannan-Rissanen start's from 3.2e4 to 4.5; the iterations from the
///    subspace start fall from 33 to 6.
///  - Initial values: ARMAX/ARMA by Hannan-Rissanen (high-order ARX, its
///    residuals as a measured noise input, then least squares for A, B, C;
///    E. J. Hannan & J. Rissanen, Biometrika 69 (1982) 81-94). ARMAX also from
///    a subspace model: MOESP-weighted n4sid (order by its SVC rule, at most
///    min(na, 20)), whose
///    innovation form gives A = det(zI - A), C = det(zI - A + KC) and B_i from
///    C adj(zI - A) B_i + D_i det(zI - A), zero-padded to the orders. Both are
///    raced a few steps in lock-step and the lower cost goes on (PemOptions::start). The
///    subspace start matters for lightly damped plants sampled fast with white
///    measurement noise (C = A, roots next to the unit circle), where the
///    high-order ARX cannot whiten the noise and
///    the Hannan-Rissanen start leads to a poor local minimum (on the Par2 log
///    its cost is 10^4 times the optimum, the subspace start's 1.5 times, both before
///    the variable projection above). On
///    request (or when n4sid fails), an output-error start instead: B, F of an OE
///    fit with nf = min(na, nc), then A = C = F zero-padded (the OE predictor).
///    OE from an ARX of
///    the same orders (F_i = the ARX A) refined by Steiglitz-McBride iterations
///    (data filtered by 1/F, K. Steiglitz & L. McBride, IEEE TAC 10 (1965) 461).
///    Unstable initial denominators are reflected into the unit circle.
///  - Parameter covariance sigma^2 (J^T J)^-1 from the final triangular factor,
///    sigma^2 = 2 V / (N - p) (Ljung 1999, eq. 9.17).
///
/// Data are mean-removed (offsets in the result) and scaled to unit RMS per
/// channel during the iterations; the model is returned in original units.
///
/// Preconditions (std::invalid_argument): orders >= 0, one nb, nf and nk per
/// input, output index in range, at least one parameter, more samples than
/// parameters. Box-Jenkins (nc or nd together with nf) is not initialised here:
/// rejected.
#include <sysid/core/io_data.hpp>
#include <sysid/pem/polynomial_model.hpp>

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

/// Where the ARMAX iterations start (other structures have one start each).
enum class PemStart {
  /// the subspace and the Hannan-Rissanen starts raced in step for up to 10
  /// iterations, ended early once one has converged below the other; the
  /// lower cost goes on (the output-error start stands in for the subspace one
  /// when that is unavailable)
  automatic,
  hannan_rissanen,  ///< high-order ARX, its residuals as noise regressors, least squares
  output_error,     ///< B, F of an OE fit with nf = min(na, nc); A = C = F (zero-padded)
  subspace          ///< the polynomials of an n4sid innovation model (order <= na), zero-padded
};

struct PemOptions {
  int na = 0;           ///< A order (ARMA/ARMAX)
  std::vector<int> nb;  ///< per input (one per input of the data)
  std::vector<int> nf;  ///< per input; empty = 0 for every input
  std::vector<int> nk;  ///< per input; empty = 1 for every input
  int nc = 0;           ///< C order
  int nd = 0;           ///< D order
  Eigen::Index output = 0;  ///< which output column the model explains
  int max_iterations = 100;
  /// Converged when the full Gauss-Newton step is shorter than this many
  /// standard deviations of the parameter estimate (Mahalanobis length
  /// ||Q^T eps|| / sigma): the data cannot tell the next iterate from this one.
  /// 0 disables the test (then only the tolerances below apply).
  double step_significance_tolerance = 0.1;
  /// ... or when the relative cost decrease of an accepted step is below this.
  double function_tolerance = 1e-10;
  /// ... or when max |J^T eps| <= gradient_tolerance * (1 + V).
  double gradient_tolerance = 1e-10;
  /// ... or when ||step|| <= parameter_tolerance * (||theta|| + parameter_tolerance).
  double parameter_tolerance = 0;
  /// ARMA/ARMAX (no D, no F): A and B re-solved by least squares for the
  /// current C at each start and after each accepted step (variable
  /// projection, header). false: plain joint Levenberg-Marquardt.
  bool variable_projection = true;
  /// High-order ARX of the Hannan-Rissanen start; 0 = min(max(3 max(na, nb, nc), 20), N / 20).
  int initial_arx_order = 0;
  int steiglitz_mcbride_iterations = 5;  ///< OE start refinement passes
  /// ARMAX only (na, nc and some nb > 0): which start(s) to iterate from.
  PemStart start = PemStart::automatic;
  bool remove_means = true;
};

struct PemResult {
  enum class Status { converged, max_iterations, failed };
  Status status = Status::failed;
  std::string termination;  ///< which criterion ended the iterations, in words
  PolynomialModel model;    ///< in original units
  Eigen::MatrixXd covariance;  ///< of the parameter vector (pack_parameters order), original units
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;  ///< 1/2 sum eps^2 in scaled units
  std::vector<double> cost_history;         ///< accepted costs, scaled units
  Eigen::VectorXd input_offset, output_offset;
  double condition = 0;  ///< of the column-scaled Jacobian at the solution (infinite: rank deficient to double precision)
  std::string structure;  ///< "armax", "arma", "oe", ... (structure_name)
  /// ARMAX/ARMA: the start the returned model was iterated from ("hannan-rissanen" or "output-error").
  std::string start;
  std::vector<std::string> warnings;
};

PemResult pem(IoData data, const PemOptions& options);

/// "ar", "arx", "arma", "armax", "oe", "bj" or "polynomial" from the orders.
std::string structure_name(int na, const std::vector<int>& nb, int nc, int nd, const std::vector<int>& nf);

/// Parameter vector [a_1..a_na, b_1 (all), ..., c_1..c_nc, d_1..d_nd, f_1 (all), ...].
Eigen::VectorXd pack_parameters(const PolynomialModel& model);
/// Inverse of pack_parameters into a model with the same orders.
void unpack_parameters(const Eigen::VectorXd& theta, PolynomialModel& model);

/// Prediction errors eps (N) of one record and, when asked, the Jacobian
/// d eps / d theta (N x p, pack_parameters order), filtered from rest.
struct PredictionErrors {
  Eigen::VectorXd eps;
  Eigen::MatrixXd jacobian;
};
PredictionErrors prediction_errors(const PolynomialModel& model, const Eigen::MatrixXd& u, const Eigen::VectorXd& y,
                                   bool with_jacobian);

/// Roots in z of a monic polynomial [1, p_1..p_n] in q^-1 (eigenvalues of its companion matrix).
Eigen::VectorXcd polynomial_roots(const Eigen::VectorXd& monic);
/// The same polynomial with every root outside the unit circle reflected to 1/conj(z) (spectral factor).
Eigen::VectorXd reflect_into_unit_circle(const Eigen::VectorXd& monic);

}  // namespace sysid
