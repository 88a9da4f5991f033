#pragma once
/// @file
/// Purpose: the output power spectral density a model predicts, on the same
/// one-sided density scale as welch_psd / periodogram (spectral/welch.hpp), and a
/// measure of its agreement with a non-parametric estimate: the check of an AR,
/// ARMA or any innovation-form model against the periodogram of the log.
///
/// Method: for the innovation model x+ = A x + B u + K e, y = C x + D u + e with
/// E[e e^T] = Lambda, the output spectrum is (Ljung 1999, eq. 2.68 and sec. 6.2;
/// Stoica & Moses 2005, eq. 1.4.9)
///
///   Phi_y(f) = G(z) Phi_u(f) G(z)^H + c(f) Ts H(z) Lambda H(z)^H,  z = exp(j 2 pi f Ts),
///   G(z) = C (zI - A)^-1 B + D,   H(z) = C (zI - A)^-1 K + I,
///
/// where Phi_u is the one-sided input cross-spectral density (e.g. welch_csd of the
/// log's inputs) and c(f) = 2 for 0 < f < fs/2, 1 at f = 0 and f = fs/2 (the
/// one-sided convention of welch_psd, whose bins sum to the variance). A time-series
/// model (AR, ARMA: no inputs) has only the second term, the whole spectrum of the
/// process. Both transfer functions come from frequency_response() (Laub 1981).
///
/// The agreement: per bin in a band, 10 log10(model / estimate) in dB (median and
/// mean absolute value) and the fraction of bins where the model lies inside the
/// estimate's chi-square confidence interval [estimate lo, estimate hi]
/// (psd_confidence_factors, spectral/confidence.hpp). For a correct model about the
/// confidence level of the bins lie inside, less at sharp peaks where the Welch
/// window's leakage biases the estimate.
///
/// Preconditions (std::invalid_argument): a discrete model (Ts > 0; discretise a
/// continuous one first); K n x l and Lambda l x l symmetric non-negative, or both
/// empty (no disturbance model: only the input part); input_csd empty or one m x m
/// matrix per frequency; a model with neither inputs nor a disturbance model has no
/// spectrum. Frequencies finite, 0 <= f <= fs/2.
/// Numerical aspects: O(n^3 + F (n^2 (m + l) + l m^2)); at a frequency on a pole
/// (an undamped mode) the spectrum is infinite, as it is.
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

struct ModelSpectrum {
  Eigen::VectorXd freq_hz;
  Eigen::MatrixXd output_psd;       ///< frequencies x outputs: the input part plus the disturbance part
  Eigen::MatrixXd disturbance_psd;  ///< frequencies x outputs: c(f) Ts H Lambda H^H alone
  /// e.g. an unstable model (a pole on or outside the unit circle) has no stationary
  /// output: its curve is still |G|^2 Phi_u + |H|^2 Lambda, but not a spectrum.
  std::vector<std::string> warnings;
};

/// Purpose: the model's one-sided output PSD (units^2/Hz), see the file comment.
/// Example: `auto s = model_output_spectrum(ss, file.K, file.noise_covariance, welch.freq_hz);`
ModelSpectrum model_output_spectrum(const StateSpace& model, const Eigen::MatrixXd& K, const Eigen::MatrixXd& noise_covariance,
                                    const Eigen::VectorXd& freq_hz, const std::vector<Eigen::MatrixXcd>& input_csd = {});

struct SpectrumAgreement {
  Eigen::Index bins = 0;         ///< bins compared (inside the band, both spectra positive and finite)
  double median_db = 0.0;        ///< median of 10 log10(model / estimate): the level offset
  double mean_abs_db = 0.0;      ///< mean of |10 log10(model / estimate)|: the shape error
  double fraction_inside = 0.0;  ///< bins where model is inside [estimate lo_factor, estimate hi_factor]
};

/// Purpose: agreement of a model spectrum with an estimate over f_lo <= f <= f_hi.
/// Preconditions (std::invalid_argument): equal sizes; f_lo < f_hi; 0 < lo_factor <=
/// 1 <= hi_factor; at least one bin compared.
SpectrumAgreement spectrum_agreement(const Eigen::VectorXd& estimate, const Eigen::VectorXd& model, const Eigen::VectorXd& freq_hz,
                                     double f_lo, double f_hi, double lo_factor, double hi_factor);

}  // namespace sysid
