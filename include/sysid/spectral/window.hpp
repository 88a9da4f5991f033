#pragma once
/// @file
/// Purpose: data tapers (windows) for spectral estimation, and the two window
/// sums the spectral scalings need.
///
/// Method: cosine-sum windows w[n] = sum_k (-1)^k a_k cos(2 pi k n / L), n = 0..L-1,
/// in their periodic ("DFT-even") form: the denominator is L, not L - 1, so the
/// window is one period of a periodic sequence and its DFT has only 2K - 1 non-zero
/// bins (F. J. Harris, "On the use of windows for harmonic analysis with the
/// discrete Fourier transform", Proc. IEEE 66 (1978) 51-83, sec. II and IV).
/// This is the form scipy.signal.welch uses (get_window(..., fftbins=True)).
/// Coefficients:
///   rectangular      a = {1}
///   hann             a = {0.5, 0.5}
///   hamming          a = {0.54, 0.46}
///   blackman_harris  a = {0.35875, 0.48829, 0.14128, 0.01168}  (Harris 1978, minimum 4-term, -92 dB sidelobes)
///   flattop          a = {0.21557895, 0.41663158, 0.277263158, 0.083578947, 0.006947368}
///                    (D'Antona & Ferrero, Digital Signal Processing for Measurement
///                    Systems, 2006; amplitude error < 0.01 dB: for reading sine amplitudes
///                    with SpectralScaling::spectrum, not for densities)
#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace sysid {

enum class WindowType { rectangular, hann, hamming, blackman_harris, flattop };

/// Name as used on the command line ("rectangular", "hann", "hamming", "blackman-harris", "flattop").
inline std::string window_name(WindowType w) {
  switch (w) {
    case WindowType::rectangular: return "rectangular";
    case WindowType::hann: return "hann";
    case WindowType::hamming: return "hamming";
    case WindowType::blackman_harris: return "blackman-harris";
    case WindowType::flattop: return "flattop";
  }
  return "unknown";
}

/// Inverse of window_name; also accepts "rect", "boxcar", "hanning", "blackmanharris",
/// "blackman_harris", "flat-top". Throws std::invalid_argument for anything else.
inline WindowType parse_window(const std::string& name) {
  if (name == "rectangular" || name == "rect" || name == "boxcar") return WindowType::rectangular;
  if (name == "hann" || name == "hanning") return WindowType::hann;
  if (name == "hamming") return WindowType::hamming;
  if (name == "blackman-harris" || name == "blackmanharris" || name == "blackman_harris") return WindowType::blackman_harris;
  if (name == "flattop" || name == "flat-top") return WindowType::flattop;
  throw std::invalid_argument("window: unknown window '" + name + "' (need one of rectangular, hann, hamming, blackman-harris, flattop)");
}

/// Purpose: the periodic window of length L (see the file comment).
/// Preconditions: L >= 1.
/// Numerical aspects: O(L); the cosines are evaluated directly (no recurrence), so
/// the values are accurate to a few ulp for any L.
inline Eigen::VectorXd make_window(WindowType type, Eigen::Index length) {
  if (length < 1) throw std::invalid_argument("window: need length >= 1");
  double a[5] = {1.0, 0.0, 0.0, 0.0, 0.0};
  int terms = 1;
  switch (type) {
    case WindowType::rectangular: break;
    case WindowType::hann: a[0] = 0.5; a[1] = 0.5; terms = 2; break;
    case WindowType::hamming: a[0] = 0.54; a[1] = 0.46; terms = 2; break;
    case WindowType::blackman_harris:
      a[0] = 0.35875; a[1] = 0.48829; a[2] = 0.14128; a[3] = 0.01168; terms = 4; break;
    case WindowType::flattop:
      a[0] = 0.21557895; a[1] = 0.41663158; a[2] = 0.277263158; a[3] = 0.083578947; a[4] = 0.006947368; terms = 5; break;
  }
  Eigen::VectorXd w(length);
  const double L = static_cast<double>(length);
  for (Eigen::Index n = 0; n < length; ++n) {
    double v = a[0];
    double sign = -1.0;
    for (int k = 1; k < terms; ++k, sign = -sign)
      v += sign * a[k] * std::cos(2.0 * std::numbers::pi * static_cast<double>(k) * static_cast<double>(n) / L);
    w(n) = v;
  }
  return w;
}

}  // namespace sysid
