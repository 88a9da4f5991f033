#pragma once
/// @file
/// Purpose: Markov parameters (the impulse response of a discrete-time system),
/// the common currency of the realisation layer:
///
///   h[0] = D,   h[k] = C A^(k-1) B  (k >= 1),   each l x m,
///
/// so that y(k) = sum_{s >= 0} h[s] u(k - s) from rest. Three sources:
///  - an FIR estimate (adaptive/multistep_nlms.hpp's Result::fir): its taps are
///    the Markov parameters directly (markov_from_fir);
///  - a state-space model (markov_parameters; for tests and comparisons);
///  - hammer-tap (impulse-like force) records: regularised deconvolution
///    (impulse_response_from_taps).
///
/// Deconvolution method: with all records stacked, the response is
///   y(k) = sum_{s=0}^{L-1} h[s] u(k - s) + e(k),   u(k < 0) = 0 in each record,
/// a linear least-squares problem Phi Theta = Y with the block-Toeplitz regressor
/// Phi (rows [u(k)^T, u(k-1)^T, ..., u(k-L+1)^T], L m columns) and
/// Theta = [h[0]^T; ...; h[L-1]^T]. It is solved with Tikhonov regularisation
///   min ||Phi Theta - Y||_F^2 + lambda^2 ||Theta||_F^2
/// in two orthogonal steps, never the normal equations: the rows [Phi Y] are
/// streamed through a Householder QR (core/streaming_qr.hpp), giving
/// [R11 R12; 0 R22]; then the small stacked matrix [R11 R12; lambda I 0] is
/// factored again by QR and Theta follows by back substitution. This keeps the
/// accuracy at cond(Phi) instead of cond(Phi)^2 — which matters here, as the
/// force spectrum of a hammer tap falls off steeply above its contact bandwidth
/// and Phi is ill conditioned there.
/// lambda = regularization * (RMS column norm of Phi). Since Phi^T Phi is close to
/// the Toeplitz matrix of the force autocorrelation, its singular values follow
/// |U(f)|: frequency bands where the force spectrum is below `regularization`
/// times its RMS level are damped rather than amplified (bias instead of noise).
///
/// Preconditions (std::invalid_argument): every record starts at rest (zero force
/// and zero response before its first sample: start the record before the tap);
/// length >= 1; total samples >= L m (equations >= unknowns); regularization >= 0.
/// Numerical aspects: O(N (L m + l)^2) flops for N samples in total, memory
/// O((L m + l)^2) whatever N.
#include <sysid/core/errors.hpp>
#include <sysid/core/io_data.hpp>
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

struct MarkovParameters {
  std::vector<Eigen::MatrixXd> h;  ///< h[0] = D, h[k] = C A^(k-1) B; each l x m
  double Ts = 0.0;                 ///< sample time in seconds (> 0)
  std::vector<std::string> input_names;   ///< m names (may be empty)
  std::vector<std::string> output_names;  ///< l names (may be empty)

  Eigen::Index outputs() const { return h.empty() ? 0 : h.front().rows(); }
  Eigen::Index inputs() const { return h.empty() ? 0 : h.front().cols(); }
  /// Number of matrices, h[0] included.
  Eigen::Index count() const { return static_cast<Eigen::Index>(h.size()); }

  std::string input_name(Eigen::Index j) const {
    return j < static_cast<Eigen::Index>(input_names.size()) ? input_names[j] : "u" + std::to_string(j + 1);
  }
  std::string output_name(Eigen::Index i) const {
    return i < static_cast<Eigen::Index>(output_names.size()) ? output_names[i] : "y" + std::to_string(i + 1);
  }

  /// Throws std::invalid_argument on: no matrices, inconsistent sizes, non-finite
  /// entries, Ts <= 0, wrong name counts.
  void validate() const;
};

/// Purpose: Markov parameters from FIR taps (fir[s] is l x m, the coefficient of
/// u(k - s); e.g. MultiStepNlmsResult::fir). The taps are copied unchanged:
/// h[s] = fir[s].
/// Preconditions: fir non-empty, equal sizes, Ts > 0 (std::invalid_argument).
MarkovParameters markov_from_fir(const std::vector<Eigen::MatrixXd>& fir, double Ts,
                                 std::vector<std::string> input_names = {},
                                 std::vector<std::string> output_names = {});

/// Purpose: the first count + 1 Markov parameters h[0..count] of a discrete model.
/// Preconditions: sys.Ts > 0, count >= 0 (std::invalid_argument).
/// Numerical aspects: O(count n^2 m) by the recursion X <- A X, X = A^(k-1) B.
MarkovParameters markov_parameters(const StateSpace& sys, int count);

struct ImpulseDeconvolutionOptions {
  /// L: number of Markov parameters estimated, h[0..L-1]. Must be given (>= 1);
  /// choose it so the response has decayed within L samples.
  int length = 0;
  /// Tikhonov weight relative to the RMS column norm of the regressor (see the
  /// file comment): 1e-3 damps bands where the force is 60 dB below its RMS level.
  double regularization = 1e-3;
};

struct ImpulseDeconvolutionResult {
  MarkovParameters markov;
  double condition = 0.0;         ///< of the column-scaled, unregularised regressor (from R11)
  double residual_rms = 0.0;      ///< RMS of y - u * h over all samples and outputs
  double lambda = 0.0;            ///< the absolute Tikhonov weight used
  Eigen::Index equations = 0;     ///< samples used (all records)
  std::vector<std::string> warnings;
};

/// Purpose: impulse response (Markov parameters) from one or several hammer-tap
/// (or any impulse-like or broadband force) records, by regularised
/// least-squares deconvolution (file comment). Each experiment of `taps` is one
/// record: u = forces (N_e x m), y = responses (N_e x l); records are never
/// concatenated in time (each starts from rest).
/// Preconditions: see the file comment (std::invalid_argument).
/// Warnings: response not decayed within the window (largest ||h[s]|| over the
/// last tenth of the window > 5 % of the largest overall, L >= 8); ill-conditioned regressor (cond > 1e8: a force with little
/// content in part of the band; regularisation decides there).
/// Throws NumericalError if the regularised system is singular (all-zero force
/// with regularization = 0).
ImpulseDeconvolutionResult impulse_response_from_taps(const IoData& taps,
                                                      const ImpulseDeconvolutionOptions& options);

}  // namespace sysid
