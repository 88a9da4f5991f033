#pragma once
/// @file
/// Purpose: the lowest modes of a large FE model — natural frequencies, mass-
/// normalised mode shapes and modal damping — the basis of a reduced model a
/// controller designer can use.
///
/// Method: the generalised symmetric eigenproblem K phi = lambda M phi by implicitly
/// restarted Lanczos (Spectra, SymGEigsShiftSolver) in shift-invert mode: the
/// iteration runs on (K - sigma M)^{-1} M, whose largest eigenvalues 1/(lambda -
/// sigma) are the lambda nearest sigma, so the lowest modes converge first and
/// fast (Ericsson & Ruhe 1980, Math. Comp. 35(152)). K - sigma M is factorised once
/// by CHOLMOD's supernodal Cholesky (Chen, Davis, Hager & Rajamanickam 2008, ACM
/// TOMS 35(3)); each Lanczos step is two triangular solves.
///
/// The shift: sigma = -(2 pi f_shift)^2, f_shift = options.rigid_body_shift_hz, a
/// little below zero. K - sigma M is then positive definite even for a
/// free-floating structure (K singular, rigid-body modes at lambda = 0), which
/// are found as frequencies ~0, and the lowest elastic modes stay the ones
/// nearest the shift, so convergence is as fast as with sigma = 0. Should
/// round-off make K - sigma M indefinite, sigma is enlarged 100-fold (up to six
/// times).
///
/// Modal damping: the projected damping matrix Phi^T C Phi (diagonal for Rayleigh
/// damping), or 2 zeta omega_i for a modal damping ratio; damping_ratios holds its
/// diagonal over 2 omega_i (NaN for rigid-body modes).
///
/// Numerical aspects: each mode's normwise backward error |K phi - lambda M phi| /
/// ((|K|_1 + |lambda| |M|_1) |phi|) is reported (max_relative_residual; a warning
/// above 1e-9); the eigenvalue problem is well
/// conditioned (symmetric), but closely spaced modes have ill-determined shapes
/// (only their span is), so tests compare frequencies and frequency responses.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "sysid/fem/second_order_model.hpp"

namespace sysid::fem {

struct ModalAnalysisOptions {
  int modes = 10;  ///< how many of the lowest modes, 1 <= modes < dofs
  /// Lanczos basis size; 0 = automatic, min(dofs, max(2 modes + 1, modes + 20)).
  int basis_size = 0;
  int max_restarts = 1000;            ///< Spectra's maxit
  double tolerance = 1e-10;           ///< Spectra's relative Ritz-value tolerance
  double rigid_body_shift_hz = 0.01;  ///< f_shift when K is singular (see file comment)
};

struct ModalAnalysisResult {
  Eigen::VectorXd natural_frequencies_hz;  ///< ascending, modes entries (0 for rigid-body modes)
  Eigen::VectorXd eigenvalues;             ///< lambda = omega^2, rad^2/s^2 (may be ~ -0 for rigid-body modes)
  Eigen::MatrixXd mode_shapes;             ///< dofs x modes, Phi^T M Phi = I
  Eigen::MatrixXd modal_damping;           ///< modes x modes: Phi^T C Phi, or diag(2 zeta omega)
  Eigen::VectorXd damping_ratios;          ///< diag(modal_damping) / (2 omega); NaN for rigid-body modes
  double shift = 0.0;                      ///< sigma used, rad^2/s^2
  long restarts = 0;                       ///< Lanczos restarts (Spectra's num_iterations)
  long operator_applications = 0;          ///< shift-invert solves (Spectra's num_operations)
  double max_relative_residual = 0.0;      ///< max over modes of the backward error (file comment)
  int rigid_body_modes = 0;                ///< modes with |lambda| below 1e-8 of the largest found
  std::vector<std::string> warnings;
};

/// Purpose: the `options.modes` lowest modes of `model` (file comment).
/// Preconditions (std::invalid_argument): model.validate(); 1 <= modes < dofs.
/// Errors: sysid::NumericalError when M is not positive definite, K - sigma M cannot
/// be factorised, or Lanczos does not converge (the message gives the restarts).
ModalAnalysisResult modal_analysis(const SecondOrderModel& model, const ModalAnalysisOptions& options = {});

}  // namespace sysid::fem
