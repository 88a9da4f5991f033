// One-factorisation Krylov frequency sweep (see fem/detail/krylov_sweep.hpp).
#include "fem/detail/krylov_sweep.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "sysid/core/errors.hpp"
#include "fem/detail/shifted_stiffness.hpp"

namespace sysid::fem::detail {

namespace {

using Complex = std::complex<double>;

/// An output entry below this fraction of its input's largest output entry is held
/// to the error that fraction allows (an exact zero by symmetry cannot be matched
/// relatively).
constexpr double kEntryFloor = 1e-4;

/// A projected modal stiffness |a lambda_i - b| below this fraction of the band's
/// stiffness scale |a| lambda_front + |b| marks a frequency as (near) an undamped
/// resonance: converged Ritz values are accurate to about 1e-12 relative, so a
/// true singularity falls well inside, and the direct solve then decides.
constexpr double kProjectedSingular = 1e-10;

/// Block Lanczos with full reorthogonalisation for the M-self-adjoint operator
/// S^-1 M (Ericsson & Ruhe 1980; Grimes, Lewis & Simon 1994, SIAM J. Matrix Anal.
/// Appl. 15(1)): V M-orthonormal, and the relation
///
///   S^-1 M V = V H + W E^T,   S^-1 F = V G,
///
/// with H = V^T M S^-1 M V (p x p, symmetric), W the part of the next block
/// M-orthogonal to V (n x q), E the last q columns of the identity.
class LanczosBasis {
 public:
  LanczosBasis(const ShiftedStiffnessFactor& factor, const Eigen::SparseMatrix<double>& mass, const Eigen::MatrixXd& forces,
               Eigen::Index capacity)
      : m_factor(factor), m_m(mass), m_v(mass.rows(), capacity), m_h(Eigen::MatrixXd::Zero(capacity, capacity)) {
    Eigen::MatrixXd t;
    Eigen::MatrixXd first = factor.solve(forces);
    const Eigen::Index q = orthonormalise_in_block(first, t);
    m_v.leftCols(q) = first.leftCols(q);
    m_g = Eigen::MatrixXd::Zero(capacity, forces.cols());
    m_g.topRows(q) = t;
    m_p = q;
    m_last = 0;
    prepare_next();
  }

  Eigen::Index size() const { return m_p; }
  bool exhausted() const { return m_w.cols() == 0; }
  auto basis() const { return m_v.leftCols(m_p); }
  Eigen::MatrixXd h() const { return m_h.topLeftCorner(m_p, m_p); }
  Eigen::MatrixXd g() const { return m_g.topRows(m_p); }
  const Eigen::MatrixXd& remainder() const { return m_w; }
  Eigen::Index last_block_start() const { return m_last; }

  /// Appends the normalised remainder W, whole (a part would break the relation
  /// the error estimate rests on), if it fits in the capacity; prepares the next.
  /// Returns false when nothing was appended.
  bool grow() {
    if (m_w.cols() == 0 || m_p + m_w.cols() > m_v.cols()) return false;
    Eigen::MatrixXd t;
    Eigen::MatrixXd block = m_w;
    const Eigen::Index q = orthonormalise_in_block(block, t);
    if (q == 0) {
      m_w.resize(m_v.rows(), 0);
      return false;
    }
    // W = Q T: the new rows of H's last block columns (H is symmetric, so the new
    // columns' rows above the block are T^T there).
    const Eigen::Index last_cols = m_p - m_last;
    m_h.block(m_p, m_last, q, last_cols) = t.leftCols(last_cols);
    m_h.block(m_last, m_p, last_cols, q) = t.leftCols(last_cols).transpose();
    m_v.middleCols(m_p, q) = block.leftCols(q);
    m_last = m_p;
    m_p += q;
    prepare_next();
    return true;
  }

 private:
  /// S^-1 M times the last block, M-orthogonalised against V (classical block
  /// Gram-Schmidt twice: Giraud, Langou & Rozloznik 2005); the coefficients are
  /// H's last block columns.
  void prepare_next() {
    const auto last = m_v.middleCols(m_last, m_p - m_last);
    m_w = m_factor.solve(m_m * Eigen::MatrixXd(last));
    Eigen::MatrixXd coefficients = Eigen::MatrixXd::Zero(m_p, m_w.cols());
    for (int pass = 0; pass < 2; ++pass) {
      const Eigen::MatrixXd c = basis().transpose() * (m_m * m_w);
      m_w.noalias() -= basis() * c;
      coefficients += c;
    }
    m_h.block(0, m_last, m_p, m_p - m_last) = coefficients;
    m_h.block(m_last, 0, m_p - m_last, m_p) = coefficients.transpose();
    // The diagonal block twice written: keep it exactly symmetric.
    auto diagonal = m_h.block(m_last, m_last, m_p - m_last, m_p - m_last);
    diagonal = (0.5 * (diagonal + diagonal.transpose())).eval();
  }

  /// Y = Q T with Q M-orthonormal (modified Gram-Schmidt twice within the block), Q
  /// written over Y's first columns; columns that lost all but 1e-10 of their
  /// M-norm are dropped (deflation). Returns Q's width.
  Eigen::Index orthonormalise_in_block(Eigen::MatrixXd& y, Eigen::MatrixXd& t) const {
    const Eigen::Index q = y.cols();
    t = Eigen::MatrixXd::Zero(q, q);
    Eigen::Index accepted = 0;
    for (Eigen::Index j = 0; j < q; ++j) {
      Eigen::VectorXd v = y.col(j);
      const double before = std::sqrt(std::max(0.0, v.dot(m_m * v)));
      for (int pass = 0; pass < 2; ++pass) {
        const Eigen::VectorXd mv = m_m * v;
        for (Eigen::Index i = 0; i < accepted; ++i) {
          const double c = y.col(i).dot(mv);
          v -= c * y.col(i);
          t(i, j) += c;
        }
      }
      const double norm = std::sqrt(std::max(0.0, v.dot(m_m * v)));
      if (!(norm > 1e-10 * before)) continue;
      t(accepted, j) = norm;
      y.col(accepted++) = v / norm;
    }
    t.conservativeResize(accepted, q);
    return accepted;
  }

  const ShiftedStiffnessFactor& m_factor;
  const Eigen::SparseMatrix<double>& m_m;
  Eigen::MatrixXd m_v, m_h, m_g, m_w;
  Eigen::Index m_p = 0, m_last = 0;
};

/// The largest eigenvalue of (K, M), from below: 30 steps of power iteration on
/// diag(M)^-1 K, then the Rayleigh quotient with the true M. Within a small factor
/// of lambda_max, which is all the conditioning estimate needs.
double largest_eigenvalue_estimate(const SecondOrderModel& model) {
  const Eigen::VectorXd mass_diagonal = model.mass.diagonal().cwiseAbs().cwiseMax(std::numeric_limits<double>::min());
  // A fixed, DOF-varying start so that no mode is missed by symmetry.
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(model.dofs(), 1.0, 2.0).array().sin();
  for (int step = 0; step < 30; ++step) {
    v = (model.stiffness * v).cwiseQuotient(mass_diagonal);
    const double norm = v.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) return std::numeric_limits<double>::infinity();
    v /= norm;
  }
  return v.dot(model.stiffness * v) / v.dot(model.mass * v);
}

/// The rows `dofs` of the basis.
Eigen::MatrixXd basis_rows(const LanczosBasis& lanczos, const std::vector<Eigen::Index>& dofs) {
  Eigen::MatrixXd rows(static_cast<Eigen::Index>(dofs.size()), lanczos.size());
  for (std::size_t i = 0; i < dofs.size(); ++i) rows.row(static_cast<Eigen::Index>(i)) = lanczos.basis().row(dofs[i]);
  return rows;
}

/// Z(omega) = a K - b M for proportional damping (header): a = 1 + j (omega beta +
/// eta), b = omega^2 - j omega alpha.
struct PencilCoefficients {
  Complex a, b;
};
PencilCoefficients pencil_coefficients(const SecondOrderModel& model, double omega) {
  const bool rayleigh = model.damping.kind == DampingKind::rayleigh;
  return {Complex(1.0, omega * (rayleigh ? model.damping.beta : 0.0) + model.structural_loss_factor()),
          Complex(omega * omega, -omega * (rayleigh ? model.damping.alpha : 0.0))};
}

}  // namespace

KrylovSweepResult krylov_sweep(const SecondOrderModel& model, const Eigen::VectorXd& omega, const KrylovSweepOptions& options) {
  if (model.damping.kind == DampingKind::matrix)
    throw std::invalid_argument("sparse_frf: the krylov method needs proportional damping (none, Rayleigh or a modal "
                                "ratio); use the direct method with a damping matrix");
  const Eigen::Index n = model.dofs(), m = static_cast<Eigen::Index>(model.inputs.size()),
                     l = static_cast<Eigen::Index>(model.outputs.size());
  const Eigen::Index nf = omega.size();
  KrylovSweepResult r;
  r.output_displacement.assign(static_cast<std::size_t>(nf), Eigen::MatrixXcd());
  if (nf == 0) return r;
  std::vector<Eigen::Index> output_dofs;
  for (const auto& out : model.outputs) output_dofs.push_back(out.dof);

  // The shift: below zero so that K - sigma0 M is positive definite even for a
  // free-floating structure; |sigma0| small against the band so the modes in it
  // stay spread out in the shift-invert spectrum 1 / (lambda - sigma0).
  const double shift_hz = options.shift_hz > 0.0 ? options.shift_hz
                                                 : std::max(omega.maxCoeff() / (2.0 * std::numbers::pi) / 20.0, 1e-3);
  const double w_shift = 2.0 * std::numbers::pi * shift_hz;
  ShiftedStiffnessFactor factor(model.stiffness, model.mass);
  r.shift = factor.factorise_below_zero(-w_shift * w_shift, 4, "sparse_frf (krylov)");
  r.symbolic_analyses = factor.symbolic_analyses();
  r.numeric_factorisations = factor.numeric_factorisations();
  const double sigma0 = r.shift;
  const double lambda_max = largest_eigenvalue_estimate(model);
  Eigen::MatrixXd forces = Eigen::MatrixXd::Zero(n, m);
  for (Eigen::Index j = 0; j < m; ++j) forces(model.inputs[static_cast<std::size_t>(j)].dof, j) = 1.0;
  const Eigen::Index max_basis = std::min(std::max(options.max_basis, m), n);
  LanczosBasis lanczos(factor, model.mass, forces, max_basis);

  std::vector<Eigen::Index> pending(static_cast<std::size_t>(nf));
  for (Eigen::Index k = 0; k < nf; ++k) pending[static_cast<std::size_t>(k)] = k;
  // Blocks are appended whole, so the basis may pass a target by less than a block.
  Eigen::Index target = std::min(max_basis, std::max<Eigen::Index>(16, 4 * m));

  while (true) {
    while (lanczos.size() < target && lanczos.grow()) {
    }
    const Eigen::Index p = lanczos.size();
    // H = Q Theta Q^T; theta_i ~ 1 / (lambda_i - sigma0), the Ritz values.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(lanczos.h());
    if (eig.info() != Eigen::Success) throw NumericalError("sparse_frf (krylov): the Lanczos matrix has no eigendecomposition");
    const Eigen::VectorXd& theta = eig.eigenvalues();
    const Eigen::MatrixXd& q = eig.eigenvectors();
    const Eigen::MatrixXd modal_forces = q.transpose() * lanczos.g();           // p x m
    const Eigen::MatrixXd output_rows = basis_rows(lanczos, output_dofs) * q;   // l x p
    const Eigen::Index last = lanczos.last_block_start();
    const Eigen::MatrixXd last_rows = q.middleRows(last, p - last);             // E^T Q
    Eigen::MatrixXd remainder_rows(l, lanczos.remainder().cols());             // W at the outputs
    for (Eigen::Index i = 0; i < l; ++i) remainder_rows.row(i) = lanczos.remainder().row(output_dofs[static_cast<std::size_t>(i)]);
    // The largest eigenvalue the basis represents (header: the uncaptured modes
    // are taken to lie above it).
    const double theta_min = theta.minCoeff();
    // Round-off floor: S is solved to about eps cond(S) in the M-norm, cond(S) =
    // (lambda_max - sigma0) / (lambda_min - sigma0) = (lambda_max - sigma0) theta_max.
    r.rounding_error_estimate = std::numeric_limits<double>::epsilon() * (lambda_max - sigma0) * theta.maxCoeff();
    const double lambda_front = theta_min > 0.0 ? sigma0 + 1.0 / theta_min : std::numeric_limits<double>::infinity();

    // Past the round-off floor no basis helps: every frequency goes to the direct
    // solves (the caller warns).
    if (!(r.rounding_error_estimate <= options.tolerance)) break;
    std::vector<Eigen::Index> still;
    for (Eigen::Index k : pending) {
      const auto [a, b] = pencil_coefficients(model, omega(k));
      // (a I + (a sigma0 - b) H) y = G, diagonal in Q.
      const Complex c = a * sigma0 - b;
      const Eigen::VectorXcd d = (c * theta.cast<Complex>()).array() + a;
      // a lambda_i - b = d_i / theta_i, singular relative to the stiffness scale of
      // the band the basis represents. 0 Hz always goes to the direct solve: a
      // rigid-body eigenvalue is resolved only to about eps lambda_max, far from
      // the exact zero that makes Z singular there.
      const double singular_below = kProjectedSingular * (std::abs(a) * lambda_front + std::abs(b));
      if (omega(k) == 0.0 || !((d.array() / theta.cast<Complex>().array()).abs().minCoeff() > singular_below)) {
        continue;  // left to the direct solve, which judges singularity
      }
      const Eigen::MatrixXcd modal_y = d.cwiseInverse().asDiagonal() * modal_forces.cast<Complex>();  // Q^T y
      const Eigen::MatrixXcd x = output_rows * modal_y;                                               // l x m
      // Error estimate (header): e ~ rho |a sigma0 - b| W E^T y.
      double rho = std::numeric_limits<double>::infinity();
      if (lambda_front > 1.05 * (b / a).real() || lanczos.exhausted())
        rho = std::max(1.0 / std::abs(a), (lambda_front - sigma0) / std::abs(a * lambda_front - b));
      if (lanczos.exhausted()) rho = 0.0;  // invariant subspace: the projection is exact
      const Eigen::MatrixXcd error = (rho * std::abs(c)) * (remainder_rows * (last_rows * modal_y));
      double worst = std::isfinite(rho) ? r.rounding_error_estimate : std::numeric_limits<double>::infinity();
      for (Eigen::Index j = 0; j < m && std::isfinite(worst); ++j) {
        const double column_scale = x.col(j).cwiseAbs().maxCoeff();
        for (Eigen::Index i = 0; i < l; ++i)
          worst = std::max(worst, std::abs(error(i, j)) / std::max(std::abs(x(i, j)), kEntryFloor * column_scale));
      }
      if (!(worst <= options.tolerance)) {
        still.push_back(k);
        continue;
      }
      r.max_estimated_error = std::max(r.max_estimated_error, worst);
      r.output_displacement[static_cast<std::size_t>(k)] = x;
      ++r.certified;
    }
    pending = std::move(still);
    if (pending.empty() || lanczos.exhausted() || lanczos.size() + lanczos.remainder().cols() > max_basis) break;
    target = std::min(max_basis, p + std::max(m, p / 4));
  }
  r.basis_size = lanczos.size();
  r.exhausted = lanczos.exhausted();
  return r;
}

}  // namespace sysid::fem::detail
