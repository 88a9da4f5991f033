// Real modal form; see include/sysid/core/real_modal_form.hpp.
#include <sysid/core/real_modal_form.hpp>

#include <limits>

namespace sysid {

RealModalStatus real_modal_form(const Eigen::MatrixXd& A, RealModalForm& form) {
  const Eigen::Index n = A.rows();
  const Eigen::EigenSolver<Eigen::MatrixXd> es(A, true);
  if (es.info() != Eigen::Success) return RealModalStatus::no_convergence;
  const Eigen::VectorXcd lambda = es.eigenvalues();
  const Eigen::MatrixXcd V = es.eigenvectors();
  form.T.resize(n, n);
  form.blocks.clear();
  Eigen::Index col = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (lambda(i).imag() == 0.0) {
      if (col + 1 > n) return RealModalStatus::unpaired;
      form.T.col(col) = V.col(i).real();
      form.blocks.push_back({col, 1, lambda(i)});
      col += 1;
    } else if (lambda(i).imag() > 0.0) {
      if (col + 2 > n) return RealModalStatus::unpaired;
      form.T.col(col) = V.col(i).real();
      form.T.col(col + 1) = V.col(i).imag();
      form.blocks.push_back({col, 2, lambda(i)});
      col += 2;
    }
  }
  return col == n ? RealModalStatus::ok : RealModalStatus::unpaired;
}

double modal_condition(const Eigen::MatrixXd& T) {
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(T).singularValues();
  return sv(sv.size() - 1) > 0 ? sv(0) / sv(sv.size() - 1) : std::numeric_limits<double>::infinity();
}

std::optional<RealModalForm> conditioned_real_modal_form(const Eigen::MatrixXd& A, double condition_limit,
                                                         double& condition) {
  condition = std::numeric_limits<double>::infinity();
  RealModalForm form;
  if (real_modal_form(A, form) != RealModalStatus::ok) return std::nullopt;
  condition = modal_condition(form.T);
  if (!(condition <= condition_limit)) return std::nullopt;
  return form;
}

Eigen::MatrixXd real_modal_block(const RealModalBlock& block) {
  Eigen::MatrixXd a(block.size, block.size);
  if (block.size == 1) a(0, 0) = block.lambda.real();
  else a << block.lambda.real(), block.lambda.imag(), -block.lambda.imag(), block.lambda.real();
  return a;
}

}  // namespace sysid
