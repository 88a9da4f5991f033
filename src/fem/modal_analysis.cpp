// Lowest modes of a sparse FE model: CHOLMOD shift-invert + Spectra Lanczos
// (see modal_analysis.hpp).
#include "sysid/fem/modal_analysis.hpp"

#include <Eigen/CholmodSupport>
#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymGEigsShiftSolver.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "sysid/core/errors.hpp"
#include "sysid/core/format_number.hpp"
#include "fem/detail/shifted_stiffness.hpp"

namespace sysid::fem {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using Cholesky = Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower>;

/// Spectra's shift-invert operator y = (K - sigma M)^{-1} x on the shared CHOLMOD
/// factor (fem/detail/shifted_stiffness.hpp).
class CholmodShiftInvert {
 public:
  using Scalar = double;

  explicit CholmodShiftInvert(detail::ShiftedStiffnessFactor& factor) : m_factor(factor) {}
  Eigen::Index rows() const { return m_factor.rows(); }
  Eigen::Index cols() const { return m_factor.rows(); }
  /// Spectra's constructor sets the shift the caller has just factorised, which
  /// then costs nothing.
  void set_shift(double sigma) {
    if (!m_factor.try_shift(sigma))
      throw NumericalError("modal_analysis: K - sigma M is not positive definite at sigma = " + format_number(sigma));
  }
  void perform_op(const double* x_in, double* y_out) const { m_factor.solve(x_in, y_out); }

 private:
  detail::ShiftedStiffnessFactor& m_factor;
};

}  // namespace

ModalAnalysisResult modal_analysis(const SecondOrderModel& model, const ModalAnalysisOptions& options) {
  model.validate();
  const Eigen::Index n = model.dofs();
  if (options.modes < 1 || options.modes >= n)
    throw std::invalid_argument("modal_analysis: need 1 <= modes < dofs (" + std::to_string(options.modes) + " of " +
                                std::to_string(n) + ")");
  if (!(options.rigid_body_shift_hz > 0.0))
    throw std::invalid_argument("modal_analysis: need rigid_body_shift_hz > 0");
  const int nev = options.modes;
  const int ncv = options.basis_size > 0
                      ? options.basis_size
                      : static_cast<int>(std::min<Eigen::Index>(n, std::max(2 * nev + 1, nev + 20)));
  if (ncv <= nev || ncv > n)
    throw std::invalid_argument("modal_analysis: need modes < basis_size <= dofs");

  {
    // M must be positive definite for the M-inner product Lanczos relies on.
    Cholesky mass_check;
    mass_check.cholmod().print = 0;
    mass_check.compute(model.mass);
    if (mass_check.info() != Eigen::Success)
      throw NumericalError("modal_analysis: the mass matrix is not positive definite (a DOF without mass? "
                           "condense massless DOFs first)");
  }

  ModalAnalysisResult r;
  detail::ShiftedStiffnessFactor factor(model.stiffness, model.mass);
  // A small negative shift (file comment), enlarged if K - sigma M is not yet
  // numerically positive definite (a singular K whose round-off eigenvalues are
  // negative beyond the first try).
  const double w_shift = 2.0 * std::numbers::pi * options.rigid_body_shift_hz;
  r.shift = factor.factorise_below_zero(-w_shift * w_shift, 7, "modal_analysis");
  CholmodShiftInvert op(factor);
  Spectra::SparseSymMatProd<double> mass_op(model.mass);
  Spectra::SymGEigsShiftSolver<CholmodShiftInvert, Spectra::SparseSymMatProd<double>, Spectra::GEigsMode::ShiftInvert>
      solver(op, mass_op, nev, ncv, r.shift);
  solver.init();
  // The nu = 1/(lambda - sigma) of largest magnitude are the lambda nearest sigma;
  // sorted by the back-transformed lambda, smallest first.
  solver.compute(Spectra::SortRule::LargestMagn, options.max_restarts, options.tolerance, Spectra::SortRule::SmallestAlge);
  r.restarts = solver.num_iterations();
  r.operator_applications = solver.num_operations();
  if (solver.info() != Spectra::CompInfo::Successful)
    throw NumericalError("modal_analysis: Lanczos did not converge to " + std::to_string(nev) + " modes in " +
                         std::to_string(r.restarts) + " restarts (basis " + std::to_string(ncv) +
                         "); raise basis_size or max_restarts");

  r.eigenvalues = solver.eigenvalues();
  r.mode_shapes = solver.eigenvectors();
  // Ascending order, whatever the solver's convention.
  std::vector<Eigen::Index> order(static_cast<std::size_t>(nev));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return r.eigenvalues(a) < r.eigenvalues(b); });
  {
    Eigen::VectorXd values(nev);
    Eigen::MatrixXd shapes(n, nev);
    for (int i = 0; i < nev; ++i) {
      values(i) = r.eigenvalues(order[static_cast<std::size_t>(i)]);
      shapes.col(i) = r.mode_shapes.col(order[static_cast<std::size_t>(i)]);
    }
    r.eigenvalues = values;
    r.mode_shapes = shapes;
  }
  // Mass normalisation (Spectra returns M-orthonormal vectors; normalising again
  // costs one product per mode and makes the contract independent of it), and a
  // sign convention: the largest entry of each shape is positive.
  const double largest = r.eigenvalues.cwiseAbs().maxCoeff();
  // 1-norms (largest absolute column sum) of K and M for the backward error.
  const auto one_norm = [](const SparseMatrix& a) {
    double best = 0.0;
    for (Eigen::Index col = 0; col < a.outerSize(); ++col) {
      double sum = 0.0;
      for (SparseMatrix::InnerIterator it(a, col); it; ++it) sum += std::abs(it.value());
      best = std::max(best, sum);
    }
    return best;
  };
  const double stiffness_norm = one_norm(model.stiffness), mass_norm = one_norm(model.mass);
  r.natural_frequencies_hz.resize(nev);
  for (int i = 0; i < nev; ++i) {
    auto phi = r.mode_shapes.col(i);
    phi /= std::sqrt(phi.dot(model.mass * phi));
    Eigen::Index at = 0;
    phi.cwiseAbs().maxCoeff(&at);
    if (phi(at) < 0.0) phi = -phi;
    const bool rigid = std::abs(r.eigenvalues(i)) <= 1e-8 * largest;
    if (rigid) ++r.rigid_body_modes;
    r.natural_frequencies_hz(i) = rigid ? 0.0 : std::sqrt(std::max(r.eigenvalues(i), 0.0)) / (2.0 * std::numbers::pi);
    // Normwise backward error (Higham, "Accuracy and Stability of Numerical
    // Algorithms", 2nd ed., sec. 7.1 applied to K - lambda M): the residual
    // relative to what the data can resolve, (|K| + |lambda| |M|) |phi|. The plain
    // |K phi - lambda M phi| / |K phi| would amplify the harmless high-wavenumber
    // round-off in phi by lambda_max / lambda.
    const Eigen::VectorXd residual = model.stiffness * phi - r.eigenvalues(i) * (model.mass * phi);
    const double scale = (stiffness_norm + std::abs(r.eigenvalues(i)) * mass_norm) * phi.norm();
    if (scale > 0.0) r.max_relative_residual = std::max(r.max_relative_residual, residual.norm() / scale);
  }

  const Eigen::VectorXd omega = r.eigenvalues.cwiseMax(0.0).cwiseSqrt();
  if (model.damping.kind == DampingKind::modal_ratio) {
    r.modal_damping = (2.0 * model.damping.ratio * omega).asDiagonal();
  } else {
    const SparseMatrix c = model.effective_damping_matrix();
    r.modal_damping = r.mode_shapes.transpose() * (c * r.mode_shapes);
    r.modal_damping = 0.5 * (r.modal_damping + r.modal_damping.transpose()).eval();
  }
  r.damping_ratios.resize(nev);
  for (int i = 0; i < nev; ++i)
    r.damping_ratios(i) = r.natural_frequencies_hz(i) > 0.0 ? r.modal_damping(i, i) / (2.0 * omega(i))
                                                            : std::numeric_limits<double>::quiet_NaN();
  if (model.damping.kind == DampingKind::matrix) {
    const double diagonal = r.modal_damping.diagonal().norm();
    const double off = (r.modal_damping - Eigen::MatrixXd(r.modal_damping.diagonal().asDiagonal())).norm();
    if (diagonal > 0.0 && off > 0.05 * diagonal)
      r.warnings.push_back("the damping matrix couples the retained modes (off-diagonal part " +
                           format_number(off / diagonal) +
                           " of the diagonal): damping_ratios are only the diagonal; reduced models keep the coupling");
  }
  if (r.max_relative_residual > 1e-9)
    r.warnings.push_back("largest eigen backward error " + format_number(r.max_relative_residual) +
                         " > 1e-9: the modes are inaccurate (tighten tolerance or enlarge basis_size)");
  return r;
}

}  // namespace sysid::fem
