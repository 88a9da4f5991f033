#pragma once
/// @file
/// Purpose: the frequency response of a large FE model, output DOFs per unit force
/// at the input DOFs, at many frequencies, without modal truncation:
///
///   Z(omega) X(omega) = F,   Z(omega) = K - omega^2 M + j omega C,
///   H(omega) = S_q(omega) X(omega)  (rows at the output DOFs; S_q = 1, j omega or
///              -omega^2 for displacement, velocity or acceleration).
///
/// Two methods (SparseFrfOptions::method):
///
/// direct: one sparse LU (UMFPACK, Davis 2004, ACM TOMS 30(2)) of the complex
/// symmetric Z per frequency. Every Z(omega) has the same sparsity pattern — the
/// union of those of K, M and C — so the fill-reducing ordering and symbolic
/// analysis are computed once and reused; each frequency costs only the numeric
/// factorisation and the m solves. The values of Z are written in place on the
/// fixed pattern (three aligned value arrays, O(nnz) per frequency), no sparse
/// matrix is assembled inside the loop. On a 2-D or 3-D mesh the numeric
/// factorisation is ~80 % of a frequency's cost (bench/README.md), so reusing the
/// analysis saves little.
///
/// krylov: ONE real Cholesky factorisation of K - sigma0 M for the whole sweep, a
/// block Lanczos basis of the shift-invert operator and a projected solve per
/// frequency (src/fem/detail/krylov_sweep.hpp), for proportional damping only (none,
/// Rayleigh, a modal ratio; std::invalid_argument with a damping matrix). Each
/// frequency's response is accepted only if an estimate of its error at every
/// output (from the Lanczos relation, free of the round-off that swamps the
/// residual of a stiff FE model) is below krylov_tolerance relative to that
/// output; frequencies that fail at krylov_max_basis, or where the projected
/// system is singular, are solved by the direct method (and counted). The estimate
/// includes a round-off floor eps cond(K - sigma0 M); a model whose floor exceeds
/// the tolerance (a finely meshed beam) is solved directly throughout, with a
/// warning that direct solves carry errors of that order too. The estimate is not
/// a proof: the tests (modal sums, 1e-8) and the benchmark (direct solves, within
/// the tolerance) check the accepted responses.
///
/// automatic (default): krylov for a sweep (>= 50 frequencies) of a large model
/// (>= 2 000 DOFs) with proportional damping, where one factorisation replaces
/// hundreds; direct otherwise.
///
/// Modal damping (DampingKind::modal_ratio) has no damping matrix; it is applied
/// as structural damping, Z = K (1 + 2 j zeta) - omega^2 M, which gives every mode
/// the damping ratio zeta at its resonance (Ewins, "Modal Testing", sec. 2.3) and
/// differs from viscous modal damping away from resonance; a warning says so.
///
/// Numerical aspects: Z is singular at a natural frequency of an undamped model
/// and at omega = 0 for a free-floating structure; such frequencies get NaN and a
/// warning naming them, never a silently huge number (the Krylov sweep hands them
/// to the direct solves, which decide). UMFPACK's reciprocal condition estimate is
/// kept for every directly solved frequency (rcond), the smallest reported.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "sysid/fem/second_order_model.hpp"

namespace sysid::fem {

enum class SparseFrfMethod { automatic, direct, krylov };

/// "automatic", "direct", "krylov"; the inverse throws std::invalid_argument naming
/// the accepted words.
const char* sparse_frf_method_name(SparseFrfMethod method);
SparseFrfMethod sparse_frf_method_from_name(const std::string& name);

struct SparseFrfOptions {
  SparseFrfMethod method = SparseFrfMethod::automatic;  ///< see the file comment
  /// krylov: the largest estimated relative error accepted for an output entry
  /// (src/fem/detail/krylov_sweep.hpp).
  double krylov_tolerance = 1e-8;
  /// krylov: at most this many basis columns (memory: 8 x dofs x krylov_max_basis
  /// bytes; 160 MB for 50 000 DOFs).
  Eigen::Index krylov_max_basis = 400;
  /// krylov: the shift sigma0 = -(2 pi krylov_shift_hz)^2 of the one factorisation;
  /// 0 (default) = 1/20 of the highest frequency asked for.
  double krylov_shift_hz = 0.0;
  /// direct: true (default): one symbolic analysis for all frequencies. false: assemble Z
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
  /// The method chosen (never automatic); with krylov, direct_frequencies says how
  /// many frequencies fell back to direct solves.
  SparseFrfMethod method = SparseFrfMethod::direct;
  /// Symbolic analyses performed: UMFPACK's for direct solves, CHOLMOD's of
  /// K - sigma0 M for the Krylov basis. A Krylov sweep that certifies every
  /// frequency does exactly one.
  long symbolic_factorisations = 0;
  long numeric_factorisations = 0;   ///< numeric factorisations performed (the same two kinds)
  long direct_frequencies = 0;       ///< frequencies solved by sparse LU
  long krylov_frequencies = 0;       ///< frequencies certified from the Krylov basis
  Eigen::Index krylov_basis_size = 0;        ///< columns of the final Krylov basis (0 for direct)
  double krylov_max_estimated_error = 0.0;   ///< largest estimated relative error over the Krylov frequencies
  /// The Krylov sweep's round-off floor eps cond(K - sigma0 M) (included in the
  /// estimate); above krylov_tolerance every frequency is solved directly, with a
  /// warning: a direct solve's errors are of the same order then.
  double krylov_rounding_error = 0.0;
  /// Smallest UMFPACK reciprocal condition estimate over the directly solved
  /// frequencies, and where; NaN when none was solved directly.
  double min_rcond = 0.0;
  double min_rcond_freq_hz = 0.0;
  std::vector<std::string> warnings;
};

/// Purpose: H at `freq_hz` (Hz, >= 0) for every output-input pair of `model`.
/// Preconditions (std::invalid_argument): model.validate(); frequencies finite and
/// >= 0. Errors: sysid::NumericalError when UMFPACK fails for a reason other than
/// singularity (out of memory).
SparseFrfResult sparse_frf(const SecondOrderModel& model, const Eigen::VectorXd& freq_hz,
                           const SparseFrfOptions& options = {});

}  // namespace sysid::fem
