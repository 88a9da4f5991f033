#pragma once
/// @file
/// Purpose: the frequency response of a large FE model, output DOFs per unit force
/// at the input DOFs, at many frequencies, without modal truncation:
///
///   Z(omega) X(omega) = F,   Z(omega) = K - omega^2 M + j omega C,
///   H(omega) = S_q(omega) X(omega)  (rows at the output DOFs; S_q = 1, j omega or
///              -omega^2 for displacement, velocity or acceleration).
///
/// Method: one sparse LU (UMFPACK, Davis 2004, ACM TOMS 30(2)) of the complex
/// symmetric Z per frequency. Every Z(omega) has the same sparsity pattern — the
/// union of those of K, M and C — so the fill-reducing ordering and symbolic
/// analysis are computed once and reused; each frequency costs only the numeric
/// factorisation and the m solves. The values of Z are written in place on the
/// fixed pattern (three aligned value arrays, O(nnz) per frequency), no sparse
/// matrix is assembled inside the loop.
///
/// Modal damping (DampingKind::modal_ratio) has no damping matrix; it is applied
/// as structural damping, Z = K (1 + 2 j zeta) - omega^2 M, which gives every mode
/// the damping ratio zeta at its resonance (Ewins, "Modal Testing", sec. 2.3) and
/// differs from viscous modal damping away from resonance; a warning says so.
///
/// Numerical aspects: Z is singular at a natural frequency of an undamped model
/// and at omega = 0 for a free-floating structure; such frequencies get NaN and a
/// warning naming them, never a silently huge number. UMFPACK's reciprocal
/// condition estimate is kept for every frequency (rcond), the smallest reported.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "sysid/fem/second_order_model.hpp"

namespace sysid::fem {

struct SparseFrfOptions {
  /// true (default): one symbolic analysis for all frequencies. false: assemble Z
  /// and factorise it from scratch at every frequency — the reference the
  /// benchmark measures the reuse against, and a fallback if a pattern-dependent
  /// ordering ever misbehaves.
  bool reuse_symbolic = true;
  /// UMFPACK's reciprocal condition estimate (its smallest/largest pivot ratio)
  /// below which a frequency is reported as singular (NaN response + warning).
  /// The forward error can reach about eps / rcond: 2 % at 1e-14. Measured: a
  /// 2 000-element free beam at 0.001 Hz has rcond 1.2e-15 and a response 8 times
  /// too small, while a 50 000-DOF beam on isolators reaches 1.6e-14 at 19 Hz
  /// (bench/fem_frf_bench.cpp), close to the threshold: a pivot ratio depends on
  /// the units, so treat values near it with care.
  double singular_rcond = 1e-14;
};

struct SparseFrfResult {
  Eigen::VectorXd freq_hz;
  std::vector<Eigen::MatrixXcd> H;  ///< per frequency: outputs x inputs
  std::vector<std::string> input_names, output_names;
  long symbolic_factorisations = 0;  ///< UMFPACK symbolic analyses performed
  long numeric_factorisations = 0;   ///< UMFPACK numeric factorisations performed
  double min_rcond = 0.0;            ///< smallest reciprocal condition estimate over the frequencies
  double min_rcond_freq_hz = 0.0;    ///< where it occurred
  std::vector<std::string> warnings;
};

/// Purpose: H at `freq_hz` (Hz, >= 0) for every output-input pair of `model`.
/// Preconditions (std::invalid_argument): model.validate(); frequencies finite and
/// >= 0. Errors: sysid::NumericalError when UMFPACK fails for a reason other than
/// singularity (out of memory).
SparseFrfResult sparse_frf(const SecondOrderModel& model, const Eigen::VectorXd& freq_hz,
                           const SparseFrfOptions& options = {});

}  // namespace sysid::fem
