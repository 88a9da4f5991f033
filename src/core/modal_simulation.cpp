// Simulation in real modal coordinates; see simulate_blockwise_modal in
// include/sysid/core/simulate.hpp.
#include <sysid/core/simulate.hpp>

namespace sysid::detail {

std::optional<ModalRecursion> modal_recursion(const StateSpace& sys, double condition_limit) {
  double condition = 0;
  std::optional<RealModalForm> form = conditioned_real_modal_form(sys.A, condition_limit, condition);
  if (!form) return std::nullopt;
  ModalRecursion modal;
  modal.Am = ModalBlockLists(form->blocks, false);
  modal.T = std::move(form->T);
  modal.T_lu.compute(modal.T);
  // An input-free model's B (n x 0) has no data: solving for it would bind a
  // reference to a null pointer (found by UBSan).
  modal.Bm = sys.B.cols() > 0 ? Eigen::MatrixXd(modal.T_lu.solve(sys.B)) : Eigen::MatrixXd(sys.order(), 0);
  modal.Cm = sys.C * modal.T;
  return modal;
}

void simulate_modal_block(const ModalRecursion& modal, const Eigen::Ref<const Eigen::MatrixXd>& u, Eigen::VectorXd& x,
                          Eigen::Ref<Eigen::MatrixXd> states) {
  const Eigen::Index b = u.rows(), n = x.size();
  if (b == 0) return;
  const ScopedFlushSubnormals flush;  // as simulate_block
  // As simulate_block: column k+1 first receives B_m u[k], then A_m x[k] is added.
  states.col(0) = x;
  if (b > 1) states.rightCols(b - 1).noalias() = modal.Bm * u.topRows(b - 1).transpose();
  for (Eigen::Index k = 0; k + 1 < b; ++k) {
    double* next = states.col(k + 1).data();
    modal.Am.product(states.col(k).data(), next, [next](Eigen::Index i) { return next[i]; });
  }
  Eigen::VectorXd last = Eigen::VectorXd::Zero(n);
  if (u.cols() > 0) last.noalias() = modal.Bm * u.row(b - 1).transpose();
  double* next = last.data();
  modal.Am.product(states.col(b - 1).data(), next, [next](Eigen::Index i) { return next[i]; });
  x = last;
}

}  // namespace sysid::detail
