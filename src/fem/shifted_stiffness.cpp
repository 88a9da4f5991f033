// CHOLMOD factor of K - sigma M (see fem/detail/shifted_stiffness.hpp).
#include "fem/detail/shifted_stiffness.hpp"

#include <Eigen/CholmodSupport>

#include <string>

#include "sysid/core/errors.hpp"

namespace sysid::fem::detail {

struct ShiftedStiffnessFactor::Cholmod {
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
};

ShiftedStiffnessFactor::ShiftedStiffnessFactor(const Eigen::SparseMatrix<double>& stiffness,
                                               const Eigen::SparseMatrix<double>& mass)
    : m_k(stiffness), m_m(mass), m_cholmod(std::make_unique<Cholmod>()) {
  m_cholmod->solver.cholmod().print = 0;  // failures are reported by the caller, not on stderr
}

ShiftedStiffnessFactor::~ShiftedStiffnessFactor() = default;

Eigen::Index ShiftedStiffnessFactor::rows() const { return m_k.rows(); }

bool ShiftedStiffnessFactor::try_shift(double sigma) {
  if (m_factorised && sigma == m_sigma) return true;
  m_factorised = false;
  Eigen::SparseMatrix<double> shifted = m_k - sigma * m_m;
  shifted.makeCompressed();
  if (m_symbolic == 0) {
    m_cholmod->solver.analyzePattern(shifted);
    ++m_symbolic;
  }
  m_cholmod->solver.factorize(shifted);
  ++m_numeric;
  m_factorised = m_cholmod->solver.info() == Eigen::Success;
  m_sigma = sigma;
  return m_factorised;
}

double ShiftedStiffnessFactor::factorise_below_zero(double sigma, int attempts, const char* who) {
  for (int attempt = 1; !try_shift(sigma); ++attempt) {
    if (attempt >= attempts)
      throw NumericalError(std::string(who) + ": K - sigma M is not positive definite down to sigma = " +
                           std::to_string(sigma) + " (is K positive semi-definite?)");
    sigma *= 100.0;
  }
  return sigma;
}

Eigen::MatrixXd ShiftedStiffnessFactor::solve(const Eigen::MatrixXd& b) const { return m_cholmod->solver.solve(b); }

void ShiftedStiffnessFactor::solve(const double* b, double* x) const {
  Eigen::Map<const Eigen::VectorXd> in(b, rows());
  Eigen::Map<Eigen::VectorXd> out(x, rows());
  out = m_cholmod->solver.solve(in);
}

}  // namespace sysid::fem::detail
