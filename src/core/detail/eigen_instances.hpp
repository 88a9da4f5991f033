#pragma once
/// @file
/// Explicit instantiation declarations of the Eigen decompositions that sysid's
/// sources, program, tests and data generators use on double (and complex double)
/// dynamic matrices: each is compiled once, in src/core/eigen_instances_*.cpp, instead
/// of in every translation unit that calls it.
///
/// Why: Eigen is header-only, so every translation unit that calls
/// `A.eigenvalues()` (core/identification_warnings.hpp does, and nearly everything
/// includes it) instantiated and optimised EigenSolver, RealSchur, the Hessenberg
/// reduction and their Householder kernels anew: measured with clang -ftime-trace,
/// about 40 % of a library translation unit's front-end time. An explicit
/// instantiation declaration (`extern template`, C++ [temp.explicit]/11) tells the
/// compiler that the definition is elsewhere, so it neither instantiates nor
/// optimises the member functions it names; calls link to the one copy.
///
/// How it is used: the build force-includes this header first in every translation
/// unit of the project's own targets (CMake precompiled header, cmake/
/// SysidCompileSpeed.cmake), never in an installed header: a consumer of the
/// installed package instantiates what it uses, as usual.
///
/// Same arithmetic: the instantiated code is Eigen's own, compiled with the same
/// flags; only where it is compiled changes (checked: the README examples' model
/// files are byte-identical).
///
/// What is listed: class templates (their out-of-class non-template members, e.g.
/// ColPivHouseholderQR::computeInPlace) and the member templates the sources call
/// with plain matrices (compute<MatrixXd>, _solve_impl<VectorXd, VectorXd>, ...). A
/// call with another argument type (an expression, a Block) still instantiates
/// locally, which is correct, only slower to compile.
#include <Eigen/Dense>

// clang-format off
#define SYSID_EIGEN_EIGENVALUE_INSTANCES(EXTERN)                                                                              \
  EXTERN template class Eigen::EigenSolver<Eigen::MatrixXd>;                                                       \
  EXTERN template Eigen::EigenSolver<Eigen::MatrixXd>&                                                             \
      Eigen::EigenSolver<Eigen::MatrixXd>::compute<Eigen::MatrixXd>(const Eigen::EigenBase<Eigen::MatrixXd>&, bool); \
  EXTERN template class Eigen::RealSchur<Eigen::MatrixXd>;                                                         \
  EXTERN template Eigen::RealSchur<Eigen::MatrixXd>&                                                               \
      Eigen::RealSchur<Eigen::MatrixXd>::compute<Eigen::MatrixXd>(const Eigen::EigenBase<Eigen::MatrixXd>&, bool); \
  EXTERN template class Eigen::HessenbergDecomposition<Eigen::MatrixXd>;                                           \
  EXTERN template class Eigen::ComplexEigenSolver<Eigen::MatrixXcd>;                                               \
  EXTERN template Eigen::ComplexEigenSolver<Eigen::MatrixXcd>&                                                     \
      Eigen::ComplexEigenSolver<Eigen::MatrixXcd>::compute<Eigen::MatrixXcd>(const Eigen::EigenBase<Eigen::MatrixXcd>&, bool); \
  EXTERN template class Eigen::ComplexSchur<Eigen::MatrixXcd>;                                                     \
  EXTERN template class Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>;                                            \
  EXTERN template Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>&                                                  \
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>::compute<Eigen::MatrixXd>(const Eigen::EigenBase<Eigen::MatrixXd>&, int); \
  EXTERN template class Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>;                                           \
  EXTERN template Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>&                                                 \
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>::compute<Eigen::MatrixXcd>(const Eigen::EigenBase<Eigen::MatrixXcd>&, int);
// (two lists, compiled side by side: src/core/eigen_instances_*.cpp)
#define SYSID_EIGEN_LINEAR_INSTANCES(EXTERN)                                                                       \
  EXTERN template class Eigen::HouseholderQR<Eigen::MatrixXd>;                                                     \
  EXTERN template class Eigen::ColPivHouseholderQR<Eigen::MatrixXd>;                                               \
  EXTERN template void Eigen::ColPivHouseholderQR<Eigen::MatrixXd>::_solve_impl<Eigen::VectorXd, Eigen::VectorXd>( \
      const Eigen::VectorXd&, Eigen::VectorXd&) const;                                                             \
  EXTERN template void Eigen::ColPivHouseholderQR<Eigen::MatrixXd>::_solve_impl<Eigen::MatrixXd, Eigen::MatrixXd>( \
      const Eigen::MatrixXd&, Eigen::MatrixXd&) const;                                                             \
  EXTERN template class Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>;                                   \
  EXTERN template class Eigen::PartialPivLU<Eigen::MatrixXd>;                                                      \
  EXTERN template class Eigen::PartialPivLU<Eigen::MatrixXcd>;                                                     \
  EXTERN template class Eigen::FullPivLU<Eigen::MatrixXd>;                                                         \
  EXTERN template class Eigen::LLT<Eigen::MatrixXd>;                                                               \
  EXTERN template class Eigen::LDLT<Eigen::MatrixXd>;                                                              \
  EXTERN template class Eigen::JacobiSVD<Eigen::MatrixXd>;                                                         \
  EXTERN template class Eigen::BDCSVD<Eigen::MatrixXd>;
// clang-format on

SYSID_EIGEN_EIGENVALUE_INSTANCES(extern)
SYSID_EIGEN_LINEAR_INSTANCES(extern)
