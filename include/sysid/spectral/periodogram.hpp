#pragma once
/// @file
/// Purpose: the (modified) periodogram: the one-segment special case of Welch's
/// estimate, over the whole record, with an optional window and zero padding.
///
/// Method: Bendat & Piersol, Random Data, 4th ed., sec. 11.5.1; Percival & Walden,
/// Spectral Analysis for Physical Applications (1993), sec. 6.3 (direct spectral
/// estimator). One segment of all N samples, detrended, tapered, zero-padded to nfft
/// and transformed; the same engine and the same scaling as welch_psd (see
/// spectral/welch.hpp), so sum_k P(f_k) fs/nfft equals the window-weighted mean square
/// (with the rectangular window and no detrend: exactly sum x^2 / N).
///
/// Preconditions (std::invalid_argument): fs > 0 finite; N >= 2; nfft == 0 (meaning N)
/// or nfft >= N; finite samples.
/// Numerical aspects: O(channels nfft log nfft); kissfft handles any nfft but is
/// fastest for lengths with small prime factors. The estimate has 2 degrees of freedom
/// per bin whatever N is (it does not converge): use welch_psd to average.
#include <sysid/spectral/welch.hpp>

#include <Eigen/Dense>
#include <stdexcept>
#include <string>

namespace sysid {

struct PeriodogramOptions {
  WindowType window = WindowType::rectangular;         ///< taper over the whole record
  Detrend detrend = Detrend::mean;                      ///< removed before the window
  Eigen::Index nfft = 0;                                ///< FFT length; 0 means N; > N zero-pads (finer grid, no new information)
  SpectralScaling scaling = SpectralScaling::density;  ///< see spectral/welch.hpp
};

/// Purpose: one-sided periodogram of every column of x (N x channels); see the file comment.
template <class Derived>
PowerSpectrum periodogram(const Eigen::MatrixBase<Derived>& x, double fs_hz, const PeriodogramOptions& options = {}) {
  const Eigen::Ref<const Eigen::MatrixXd> xr(x.derived());
  const Eigen::Index n = xr.rows();
  if (!(fs_hz > 0.0) || !std::isfinite(fs_hz)) throw std::invalid_argument("periodogram: need 0 < fs < infinity");
  if (n < 2) throw std::invalid_argument("periodogram: need N >= 2 samples");
  if (options.nfft != 0 && options.nfft < n)
    throw std::invalid_argument("periodogram: need nfft == 0 or nfft >= N (have nfft " + std::to_string(options.nfft) +
                                ", N " + std::to_string(n) + ")");
  detail::check_finite(xr, "periodogram", "x");
  const Eigen::Index nfft = options.nfft == 0 ? n : options.nfft;
  const detail::SegmentPlan plan = detail::make_segment_plan(n, nfft, n, options.window, options.detrend);
  return detail::auto_spectra(xr, fs_hz, plan, options.scaling);
}

}  // namespace sysid
