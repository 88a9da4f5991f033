#pragma once
/// @file
/// Purpose: a sparse Cholesky factor of the shifted stiffness K - sigma M, the
/// shift-invert operator shared by modal_analysis (Lanczos) and sparse_frf's
/// Krylov sweep. CHOLMOD's supernodal LL^T (Chen, Davis, Hager & Rajamanickam
/// 2008, ACM TOMS 35(3)); the symbolic analysis of the pattern of K + M is done
/// once however often the shift changes. CHOLMOD stays out of this header.
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <memory>

namespace sysid::fem::detail {

class ShiftedStiffnessFactor {
 public:
  /// Keeps references: `stiffness` and `mass` must outlive the factor.
  ShiftedStiffnessFactor(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass);
  ~ShiftedStiffnessFactor();
  ShiftedStiffnessFactor(const ShiftedStiffnessFactor&) = delete;
  ShiftedStiffnessFactor& operator=(const ShiftedStiffnessFactor&) = delete;

  /// Factorises K - sigma M; false when it is not numerically positive definite.
  /// A repeated call with the shift already factorised costs nothing.
  bool try_shift(double sigma);

  /// For K positive semi-definite and M positive definite, K - sigma M is positive
  /// definite for every sigma < 0, but round-off can make it indefinite when K is
  /// singular and |sigma| tiny. Tries `sigma` (< 0), then 100x larger magnitudes,
  /// `attempts` times in all; returns the shift factorised. Throws
  /// sysid::NumericalError naming `who` when none works (K indefinite).
  double factorise_below_zero(double sigma, int attempts, const char* who);

  /// (K - sigma M)^{-1} b for the shift last factorised (one column or several).
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  void solve(const double* b, double* x) const;  ///< one column of length rows()

  Eigen::Index rows() const;
  double shift() const { return m_sigma; }
  long symbolic_analyses() const { return m_symbolic; }
  long numeric_factorisations() const { return m_numeric; }

 private:
  struct Cholmod;
  const Eigen::SparseMatrix<double>& m_k;
  const Eigen::SparseMatrix<double>& m_m;
  std::unique_ptr<Cholmod> m_cholmod;
  bool m_factorised = false;
  double m_sigma = 0.0;
  long m_symbolic = 0, m_numeric = 0;
};

}  // namespace sysid::fem::detail
