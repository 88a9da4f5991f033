#pragma once
/// @file
/// Purpose: one-sided power spectral density of each column of a signal by
/// Welch's method of averaged modified periodograms.
///
/// Method: P. D. Welch, "The use of fast Fourier transform for the estimation of
/// power spectra", IEEE Trans. Audio Electroacoust. 15 (1967) 70-73. Segments of
/// nfft samples with the given overlap, each detrended by its mean and tapered
/// by a Hann window; scaled so that the integral of the PSD over 0..fs/2 equals
/// the variance (density scaling, units^2/Hz).
///
/// Preconditions: nfft >= 8, 0 <= overlap < 1, N >= nfft (else nfft is reduced
/// to the largest power of two <= N).
#include <Eigen/Dense>
#include <unsupported/Eigen/FFT>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace sysid {

struct WelchOptions {
  Eigen::Index nfft = 1024;  ///< segment length
  double overlap = 0.5;      ///< fraction of a segment shared with the next
};

struct PowerSpectrum {
  Eigen::VectorXd freq_hz;  ///< nfft/2 + 1 frequencies, 0..fs/2
  Eigen::MatrixXd psd;      ///< frequencies x channels, units^2/Hz
  Eigen::Index segments = 0;
};

template <class Derived>
PowerSpectrum welch_psd(const Eigen::MatrixBase<Derived>& x, double fs_hz, const WelchOptions& options = {}) {
  if (!(fs_hz > 0)) throw std::invalid_argument("welch: need fs > 0");
  if (options.nfft < 8) throw std::invalid_argument("welch: need nfft >= 8");
  if (!(options.overlap >= 0 && options.overlap < 1)) throw std::invalid_argument("welch: need 0 <= overlap < 1");
  const Eigen::Index n = x.rows();
  if (n < 8) throw std::invalid_argument("welch: need at least 8 samples");
  Eigen::Index nfft = options.nfft;
  while (nfft > n) nfft /= 2;
  const Eigen::Index step = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::lround(nfft * (1.0 - options.overlap))));
  const Eigen::Index bins = nfft / 2 + 1;
  Eigen::VectorXd window(nfft);
  for (Eigen::Index k = 0; k < nfft; ++k)
    window(k) = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(nfft));
  const double window_power = window.squaredNorm();
  PowerSpectrum out;
  out.freq_hz = Eigen::VectorXd::LinSpaced(bins, 0.0, fs_hz / 2.0);
  out.psd = Eigen::MatrixXd::Zero(bins, x.cols());
  Eigen::FFT<double> fft;
  std::vector<double> segment(static_cast<std::size_t>(nfft));
  std::vector<std::complex<double>> spectrum;
  for (Eigen::Index start = 0; start + nfft <= n; start += step) {
    ++out.segments;
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      const double mean = x.col(c).segment(start, nfft).mean();
      for (Eigen::Index k = 0; k < nfft; ++k) segment[static_cast<std::size_t>(k)] = (x(start + k, c) - mean) * window(k);
      fft.fwd(spectrum, segment);
      for (Eigen::Index b = 0; b < bins; ++b) out.psd(b, c) += std::norm(spectrum[static_cast<std::size_t>(b)]);
    }
  }
  // One-sided density: double every bin but DC and Nyquist.
  out.psd /= (fs_hz * window_power * static_cast<double>(out.segments));
  out.psd.middleRows(1, bins - 2) *= 2.0;
  return out;
}

}  // namespace sysid
