#pragma once
/// @file
/// Internals of reduce/gramians.hpp shared by several compiled parts
/// (src/reduce/gramians.cpp, src/reduce/hankel_singular_values.cpp); defined in src/reduce/gramians.cpp.
/// The method (Hammarling 1982) is described in reduce/gramians.hpp.
#include <Eigen/Dense>

namespace sysid::detail {

/// A = U T U^H, T upper triangular (complex Schur form).
struct ComplexSchurForm {
  Eigen::MatrixXcd T;
  Eigen::MatrixXcd U;
};

/// Complex Schur form of a real matrix: real Schur form, then one unitary 2x2
/// rotation per 2x2 diagonal block (reduce/gramians.hpp file comment, step 1).
/// Throws NumericalError if the QR iteration does not converge.
ComplexSchurForm complex_schur_from_real(const Eigen::MatrixXd& A);

/// Lc (n x n, lower triangular) with Lc Lc^T = Wc of (A, B), for A = s.U s.T s.U^H
/// (file comment, steps 2 and 4). Throws std::invalid_argument if A is not
/// strictly stable.
Eigen::MatrixXd controllability_factor_from_schur(const ComplexSchurForm& s, const Eigen::MatrixXd& B, bool discrete);

/// Lo (n x n, lower triangular) with Lo Lo^T = Wo of (A, C), from the same Schur
/// form (file comment, step 3). Throws std::invalid_argument if A is not strictly stable.
Eigen::MatrixXd observability_factor_from_schur(const ComplexSchurForm& s, const Eigen::MatrixXd& C, bool discrete);

}  // namespace sysid::detail
