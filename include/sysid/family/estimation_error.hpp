#pragma once
/// @file
/// Purpose: how far an identified model's frequency response may be from the
/// plant's because of the noise in its log: the allowance a family's uncertainty
/// bound adds so that it covers the true members, not only the estimated ones.
///
/// Method: the asymptotic variance of a black-box transfer-function estimate of
/// order n from N samples (Ljung 1985, "Asymptotic variance expressions for
/// identified black-box transfer function models", IEEE TAC 30(9); Ljung,
/// System Identification, 2nd ed., eq. 9.62):
///     Cov G_hat(e^{j w}) ~ (n / N) Phi_v(w) / Phi_u(w),
/// with Phi_v the spectrum of the output error v = y - G_hat u (the model's
/// simulation on its own log, x0 estimated) and Phi_u the input spectrum, both by
/// Welch (Hann, nfft = N/8 clamped to 64..1024). With several channels the
/// scalar bound lambda_max(Phi_v) / lambda_min(Phi_u) of the largest singular
/// value's variance is used. The standard deviation is reported per Welch bin,
/// with the band the inputs excite (spectral/excited_band.hpp); outside it Phi_u
/// is near zero and the standard deviation is large, as it should be.
///
/// Preconditions: a discrete model with the log's inputs and outputs; the log's
/// first experiment is used.
#include <sysid/core/io_data.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/validate/compare.hpp>

#include <Eigen/Dense>

namespace sysid {

struct FrequencyResponseError {
  Eigen::VectorXd freq_hz;             ///< Welch bins
  Eigen::VectorXd standard_deviation;  ///< of sigma_max(G_hat) per bin, in the model's units
  double band_lo_hz = 0.0, band_hi_hz = 0.0;  ///< band the inputs excite

  /// Linear interpolation onto `grid_hz` (constant beyond the ends); empty when this is empty.
  Eigen::VectorXd at(const Eigen::VectorXd& grid_hz) const;
};

/// Purpose: the model's frequency-response standard deviation from its log (file comment).
/// `offsets`: the input/output offsets the model was identified with (CompareOptions).
FrequencyResponseError frequency_response_error(const StateSpace& model, const IoData& log, const CompareOptions& offsets = {});

/// The same from a simulation already at hand: the model's order, the log's inputs
/// u (N x m), its output error y - y_hat (N x l) and the sample time.
FrequencyResponseError frequency_response_error(Eigen::Index order, const Eigen::MatrixXd& u, const Eigen::MatrixXd& output_error,
                                                double Ts);

}  // namespace sysid
