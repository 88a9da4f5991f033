#pragma once
/// @file
/// Purpose: time-domain simulation of a discrete-time state-space model
///
///   x[k+1] = A x[k] + B u[k],   y[k] = C x[k] + D u[k],   k = 0 .. N-1.
///
/// Method: the input term B u[k] of a whole block of samples is formed with one
/// matrix product (B U^T), the state recursion then adds A x[k] column by column
/// in place, and the outputs of the block follow from one more product
/// (Y = X^T C^T + U D^T). All heavy work is GEMM; the only per-sample work is one
/// n x n GEMV into preallocated storage (no heap allocation per step).
/// simulate() processes the record in blocks of kSimulateBlock samples with a
/// fixed n x block workspace, so its memory is O(n * block + N * l) whatever N is.
///
/// Preconditions: Ts > 0 (discrete model), u.cols() == m, x0 empty or of size n.
/// Numerical aspects: O(N (n^2 + n m + l n + l m)) flops; the recursion is the
/// textbook one, so an unstable model grows as it should and nothing is clipped.
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <stdexcept>
#include <string>

namespace sysid {

namespace detail {

/// Samples per block in simulate(): large enough that the block GEMMs run at full
/// speed, small enough that the n x block state workspace stays in cache.
inline constexpr Eigen::Index kSimulateBlock = 4096;

inline void check_simulation_args(const StateSpace& sys, Eigen::Index u_cols, const Eigen::VectorXd& x0, const char* who) {
  sys.validate();
  if (!sys.is_discrete())
    throw std::invalid_argument(std::string(who) + ": need Ts > 0 (a discrete-time model); discretise with c2d_zoh first");
  if (u_cols != sys.inputs())
    throw std::invalid_argument(std::string(who) + ": need u.cols() == inputs (" + std::to_string(u_cols) +
                                " != " + std::to_string(sys.inputs()) + ")");
  if (x0.size() != 0 && x0.size() != sys.order())
    throw std::invalid_argument(std::string(who) + ": need x0.size() == order or 0 (" + std::to_string(x0.size()) +
                                " != " + std::to_string(sys.order()) + ")");
}

/// Runs the recursion over the rows of `u` (b x m) starting from state `x`.
/// On return column k of `states` (n x b) holds x[k] and `x` holds x[b].
inline void simulate_block(const StateSpace& sys, const Eigen::Ref<const Eigen::MatrixXd>& u, Eigen::VectorXd& x,
                           Eigen::Ref<Eigen::MatrixXd> states) {
  const Eigen::Index b = u.rows();
  if (b == 0) return;
  const Eigen::Index n = sys.order();
  if (n == 0) return;
  // Column k+1 first receives B u[k]; the recursion then adds A x[k] in place.
  states.col(0) = x;
  if (b > 1) states.rightCols(b - 1).noalias() = sys.B * u.topRows(b - 1).transpose();
  for (Eigen::Index k = 0; k + 1 < b; ++k) states.col(k + 1).noalias() += sys.A * states.col(k);
  // An input-free model (AR, ARMA: m = 0) has an empty u whose data pointer is
  // null: forming a row of it would offset that pointer (undefined behaviour,
  // found by UBSan).
  if (u.cols() > 0) x.noalias() = sys.B * u.row(b - 1).transpose();
  else x.setZero();
  x.noalias() += sys.A * states.col(b - 1);
}

}  // namespace detail

/// Purpose: simulated state trajectory x[0..N-1] (N x n, samples in rows).
/// Preconditions: sys.Ts > 0; u is N x m; x0 empty (zero initial state) or of size n.
/// Numerical aspects: stores all N x n states; see simulate() for the output only.
template <class Derived>
Eigen::MatrixXd simulate_states(const StateSpace& sys, const Eigen::MatrixBase<Derived>& u,
                                const Eigen::VectorXd& x0 = Eigen::VectorXd()) {
  detail::check_simulation_args(sys, u.cols(), x0, "simulate_states");
  // A column-major matrix (or a column-major block of one) is used in place; an
  // expression or a row-major matrix is evaluated once here.
  const Eigen::Ref<const Eigen::MatrixXd> uref(u.derived());
  const Eigen::Index n = sys.order(), N = u.rows();
  Eigen::VectorXd x = x0.size() == 0 ? Eigen::VectorXd(Eigen::VectorXd::Zero(n)) : x0;
  Eigen::MatrixXd states(n, N);  // column-major n x N: each state is contiguous
  detail::simulate_block(sys, uref, x, states);
  return states.transpose();
}

/// Purpose: the output of simulate(), handed over block by block, for callers
/// that only accumulate from it (a fit, a residual norm): memory O(n * block +
/// block * l) instead of O(N l). consume(k0, y_block) receives the rows
/// k0 .. k0 + b - 1 of the output (b <= 4096; y_block is valid during the call).
/// Preconditions and arithmetic are simulate()'s (bit-identical blocks).
template <class Derived, class Consumer>
void simulate_blockwise(const StateSpace& sys, const Eigen::MatrixBase<Derived>& u, const Eigen::VectorXd& x0,
                        Consumer&& consume) {
  detail::check_simulation_args(sys, u.cols(), x0, "simulate");
  const Eigen::Ref<const Eigen::MatrixXd> uref(u.derived());  // no copy for column-major storage
  const Eigen::Index n = sys.order(), N = u.rows();
  Eigen::VectorXd x = x0.size() == 0 ? Eigen::VectorXd(Eigen::VectorXd::Zero(n)) : x0;
  Eigen::MatrixXd states(n, std::min(N, detail::kSimulateBlock)), y(std::min(N, detail::kSimulateBlock), sys.outputs());
  for (Eigen::Index k0 = 0; k0 < N; k0 += detail::kSimulateBlock) {
    const Eigen::Index b = std::min(detail::kSimulateBlock, N - k0);
    const Eigen::Ref<const Eigen::MatrixXd> ub = uref.middleRows(k0, b);
    Eigen::Ref<Eigen::MatrixXd> xb = states.leftCols(b);
    detail::simulate_block(sys, ub, x, xb);
    Eigen::Ref<Eigen::MatrixXd> yb = y.topRows(b);
    yb.noalias() = xb.transpose() * sys.C.transpose();
    yb.noalias() += ub * sys.D.transpose();
    consume(k0, yb);
  }
}

/// Purpose: simulated output y[0..N-1] (N x l) of a discrete-time model for input
/// u (N x m) from initial state x0 (empty = zero).
/// Method: block recursion described in the file comment (simulate_blockwise).
/// Preconditions: sys.Ts > 0 (throws std::invalid_argument otherwise);
/// u.cols() == sys.inputs(); x0.size() in {0, n}.
/// Numerical aspects: O(N (n^2 + n m + l n + l m)) flops, memory O(n * 4096 + N l).
/// Example: `Eigen::MatrixXd y = simulate(model, data.experiments[0].u);`
template <class Derived>
Eigen::MatrixXd simulate(const StateSpace& sys, const Eigen::MatrixBase<Derived>& u,
                         const Eigen::VectorXd& x0 = Eigen::VectorXd()) {
  Eigen::MatrixXd y(u.rows(), sys.outputs());
  simulate_blockwise(sys, u, x0, [&y](Eigen::Index k0, const Eigen::Ref<Eigen::MatrixXd>& yb) {
    y.middleRows(k0, yb.rows()) = yb;
  });
  return y;
}

}  // namespace sysid
