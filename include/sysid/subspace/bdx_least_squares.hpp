#pragma once
/// @file
/// Purpose: B, D and one initial state x0 per experiment by linear least squares
/// on the simulation error, with A and C fixed — step 6 of n4sid
/// (subspace/n4sid.hpp), the approach of SLICOT IB01CD and of MATLAB's n4sid
/// with 'Focus', 'simulation'.
///
/// Method: the output is linear in B, D and x0,
///   y(t) = C A^t x0 + sum_{tau<t} C A^{t-1-tau} B u(tau) + D u(t).
/// The regressor of B(p,q) at output r is Psi_q(t)(r,p), with the l x n
/// recursion Psi_q(t+1) = Psi_q(t) A + u_q(t) C; that of x0 is Lambda(t) = C A^t.
/// The stacked regression's triangle comes from one of two routes, its columns
/// equilibrated before a rank-revealing solve of the small triangle:
///  - Gram (tried first): X^T X and X^T y accumulated by symmetric rank-k
///    updates of blocks of rows (BLAS-3), equilibrated, then Cholesky. Taken
///    only when the factorisation succeeds and the estimate of the equilibrated
///    Gram's condition number is at most `max_gram_condition` (1e6): the
///    normal equations' relative error in the solution, ~eps cond(G), is then
///    below ~2e-10; Householder QR's own error on a noisy regression carries a
///    cond(X)^2 tan(residual angle) term of the same kind (Golub & Van Loan,
///    "Matrix Computations", 4th ed., sec. 5.3.8), so both are far below the
///    data's statistical error. 2.6x faster than the QR on 22 columns.
///  - QR: a streaming Householder QR (core/streaming_qr.hpp), backward stable,
///    for ill-conditioned or rank-deficient regressions (an input that is
///    constant zero, collinear inputs), where the Gram route declines.
///
///  - Modal coordinates. In the real modal form A = T A_m T^-1
///    (core/real_modal_form.hpp; A_m block diagonal with 1x1 and 2x2
///    blocks) the recursion costs O(n) per input and sample instead of O(n^2):
///    B = T B_m, x0 = T x0_m are fitted for (A_m, C T). Used when cond(T) is at
///    most `modal_condition_limit`: the change of coordinates then costs at most
///    that factor in the regression's condition, and A_m differs from T^-1 A T
///    by about eps cond(T) ||A|| (the eigensolver's backward error). Otherwise (a
///    nearly defective A) the recursion runs on A itself.
///  - Decayed initial response. For a stable A the x0 regressors C A^t decay;
///    once every entry is below 1e-17 of its largest value so far, the row's x0
///    entries are taken as zero (a perturbation below the QR's own rounding) and
///    the row goes to a narrower QR over the B, D and y columns, merged into the
///    full triangle at the end: [R_full; R_reduced with zero x0 columns] has the
///    same R factor as the whole regression.
///  - Two cores. An experiment of at least 8 192 samples is cut in two pieces
///    with their own QRs, merged in a fixed order (so the result does not depend
///    on the number of cores; core/parallel_for.hpp). The second piece first runs
///    the recursion alone up to its first sample (the same products in the same
///    order as a single pass: bit-identical states).
///
/// Preconditions: A n x n, C l x n, data with m >= 1 inputs and l outputs;
/// violations throw std::invalid_argument.
///
/// Numerical aspects: cost O(N l p^2) for the Gram or QR, p = n m + l m + n x
/// experiments, plus O(N n m) (modal) or O(N n^2 m) for the recursion; memory
/// O(p^2) per piece besides the data. `condition` (of the column-scaled
/// triangle's diagonal) above ~1e10 means poorly excited input directions.
#include <sysid/core/io_data.hpp>

#include <Eigen/Dense>
#include <vector>

namespace sysid {

struct BdxLeastSquaresOptions {
  /// Per experiment, only the first max_samples samples enter the regression:
  /// it bounds the cost; 50 000 samples determine B, D and x0 far beyond the
  /// noise level for the orders used in system identification.
  Eigen::Index max_samples = 50000;
  /// Largest cond(T) of A's real modal form for which the recursion runs in
  /// modal coordinates (0: never). 1e3 loses at most three digits of the
  /// regression's conditioning against sixteen of the arithmetic.
  double modal_condition_limit = 1e3;
  /// Largest estimated condition number of the column-equilibrated Gram matrix
  /// for which the normal equations are solved (0: always the QR route); see
  /// the file comment. A declined Gram route costs one more pass over the data.
  double max_gram_condition = 1e6;
};

struct BdxLeastSquaresResult {
  Eigen::MatrixXd B, D;
  std::vector<Eigen::VectorXd> x0;  ///< one per experiment
  Eigen::Index samples_used = 0;
  Eigen::Index rows_without_initial_response = 0;  ///< samples whose x0 regressors had decayed (narrower QR)
  double condition = 0;           ///< of the column-scaled regression's triangle (diagonal ratio)
  bool normal_equations = false;  ///< the Gram route was taken (else the QR route)
  bool modal_coordinates = false;  ///< the recursion ran in A's real modal form
  /// cond(T) of A's real modal form (infinity when it does not exist).
  double modal_condition = 0;
};

/// B, D and x0 of every experiment of `data` for the given A and C.
BdxLeastSquaresResult bdx_least_squares(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, const IoData& data,
                                        const BdxLeastSquaresOptions& options = {});

}  // namespace sysid
