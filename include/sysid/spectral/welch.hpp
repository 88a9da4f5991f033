#pragma once
/// @file
/// Purpose: one-sided auto- and cross-spectral densities by Welch's method of
/// averaged modified periodograms, and the segment/FFT engine every spectral
/// estimate of sysid (periodogram, FRF) runs on.
///
/// Method: P. D. Welch, "The use of fast Fourier transform for the estimation of
/// power spectra", IEEE Trans. Audio Electroacoust. 15 (1967) 70-73; Bendat &
/// Piersol, Random Data, 4th ed., sec. 11.5. The record is cut into K segments of
/// L = nfft samples, consecutive starts `step = round(nfft (1 - overlap))` apart
/// (a trailing partial segment is dropped). Each segment is detrended (none, its
/// mean, or its least-squares line), multiplied by the window w and transformed
/// (Eigen's FFT module, kissfft backend). With X_i the DFT of channel i,
///   S_xy(f_k) = c_k / (fs sum_n w_n^2 K) sum_segments conj(X(k)) Y(k)   (density, units^2/Hz),
///   S_xy(f_k) = c_k / ((sum_n w_n)^2 K) sum_segments conj(X(k)) Y(k)   (spectrum, units^2),
/// f_k = k fs / nfft, k = 0..floor(nfft/2), c_k = 2 except at DC and (even nfft)
/// Nyquist where c_k = 1 (one-sided). Density scaling makes sum_k S_xx(f_k) fs/nfft
/// equal the window-weighted mean square (Parseval), i.e. the variance in
/// expectation; spectrum scaling makes a sine of amplitude A show A^2/2 at its bin
/// (exactly with the flattop window). The conjugate is on the first argument, as in
/// Bendat & Piersol's G_xy and in scipy.signal.csd, so for y = h * x,
/// S_xy = H S_xx.
///
/// Equivalent degrees of freedom (Welch 1967, eq. for overlapped segments;
/// Percival & Walden 1993, eq. 292b):
///   nu = 2 K / (1 + 2 sum_{j=1}^{K-1} (1 - j/K) rho_j^2),
///   rho_j = sum_n w_n w_{n + j step} / sum_n w_n^2,
/// valid for every bin but DC and Nyquist (real-valued there: nu/2), for a
/// Gaussian signal whose spectrum is smooth over the window's bandwidth. For
/// several records the degrees of freedom add.
///
/// Numerical aspects: every channel of every segment is transformed exactly once;
/// a cross-spectrum then costs one complex multiply-add per bin per channel pair
/// (vectorised over the contiguous bins). Total cost for p + q channels:
/// O(K (p + q) nfft log nfft + K (nfft/2) p q); memory O(nfft (p + q + p q)); no
/// allocation inside the segment loop. The sums are plain running sums in double
/// precision (K is at most ~1e6, so the relative rounding error stays ~1e-10).
#include <sysid/spectral/window.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/FFT>
#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sysid {

/// What is removed from each segment before windowing.
enum class Detrend { none, mean, linear };

/// "none", "mean", "linear"; std::invalid_argument otherwise.
inline Detrend detrend_from_name(const std::string& name) {
  if (name == "none") return Detrend::none;
  if (name == "mean") return Detrend::mean;
  if (name == "linear") return Detrend::linear;
  throw std::invalid_argument("detrend: expected 'none', 'mean' or 'linear', found '" + name + "'");
}
/// Density (units^2/Hz, integrates to the variance) or spectrum (units^2, reads sine powers).
enum class SpectralScaling { density, spectrum };

struct WelchOptions {
  /// Segment length = FFT length, >= 8. When the record is shorter it is halved
  /// until it fits (from a power of two: the largest power of two <= N).
  Eigen::Index nfft = 1024;
  double overlap = 0.5;                                 ///< fraction of a segment shared with the next, 0 <= overlap < 1
  WindowType window = WindowType::hann;                 ///< taper of every segment
  Detrend detrend = Detrend::mean;                      ///< removed from every segment before the window
  SpectralScaling scaling = SpectralScaling::density;  ///< see the file comment
};

struct PowerSpectrum {
  Eigen::VectorXd freq_hz;    ///< nfft/2 + 1 frequencies k fs / nfft
  Eigen::MatrixXd psd;        ///< frequencies x channels, units^2/Hz (density) or units^2 (spectrum)
  Eigen::Index segments = 0;  ///< number of averaged segments K
  double dof = 0.0;           ///< equivalent degrees of freedom nu of each bin but DC and Nyquist
  Eigen::Index nfft = 0;      ///< FFT length actually used
};

struct CrossSpectrum {
  Eigen::VectorXd freq_hz;  ///< nfft/2 + 1 frequencies k fs / nfft
  /// One p x q matrix per frequency: csd[k](i, j) = S_{x_i y_j}(f_k) (conjugate on x_i).
  std::vector<Eigen::MatrixXcd> csd;
  Eigen::Index segments = 0;  ///< number of averaged segments K
  double dof = 0.0;           ///< equivalent degrees of freedom nu of each bin but DC and Nyquist
  Eigen::Index nfft = 0;      ///< FFT length actually used
};

namespace detail {

/// Segmentation, taper and detrend shared by all estimates.
struct SegmentPlan {
  Eigen::Index length = 0;  ///< samples per segment
  Eigen::Index nfft = 0;    ///< FFT length >= length (zeros appended)
  Eigen::Index step = 1;    ///< samples between consecutive segment starts
  Eigen::Index bins = 0;    ///< nfft/2 + 1
  Eigen::VectorXd window;   ///< length
  Detrend detrend = Detrend::mean;
  Eigen::VectorXd ramp;     ///< n - (length-1)/2: orthogonal to a constant, so mean and slope decouple
  double ramp_norm2 = 0.0;
  double sum_w = 0.0, sum_w2 = 0.0;

  Eigen::Index segments_in(Eigen::Index n) const { return n < length ? 0 : 1 + (n - length) / step; }
};

inline SegmentPlan make_segment_plan(Eigen::Index length, Eigen::Index nfft, Eigen::Index step, WindowType window,
                                     Detrend detrend) {
  SegmentPlan p;
  p.length = length;
  p.nfft = nfft;
  p.step = step;
  p.bins = nfft / 2 + 1;
  p.window = make_window(window, length);
  p.detrend = detrend;
  p.ramp = Eigen::VectorXd::LinSpaced(length, 0.0, static_cast<double>(length - 1)).array() - 0.5 * static_cast<double>(length - 1);
  p.ramp_norm2 = p.ramp.squaredNorm();
  p.sum_w = p.window.sum();
  p.sum_w2 = p.window.squaredNorm();
  return p;
}

/// Checks fs and the Welch options and builds the plan for records of at least
/// `shortest` samples. `who` names the caller in messages.
inline SegmentPlan welch_plan(Eigen::Index shortest, double fs_hz, const WelchOptions& o, const std::string& who) {
  if (!(fs_hz > 0.0) || !std::isfinite(fs_hz)) throw std::invalid_argument(who + ": need 0 < fs < infinity");
  if (o.nfft < 8) throw std::invalid_argument(who + ": need nfft >= 8");
  if (!(o.overlap >= 0.0 && o.overlap < 1.0)) throw std::invalid_argument(who + ": need 0 <= overlap < 1");
  if (shortest < 8) throw std::invalid_argument(who + ": need at least 8 samples per record (have " + std::to_string(shortest) + ")");
  Eigen::Index nfft = o.nfft;
  while (nfft > shortest) nfft /= 2;
  const Eigen::Index step =
      std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::lround(static_cast<double>(nfft) * (1.0 - o.overlap))));
  return make_segment_plan(nfft, nfft, step, o.window, o.detrend);
}

/// Welch's equivalent degrees of freedom for K segments (file comment).
inline double welch_dof(const SegmentPlan& p, Eigen::Index K) {
  if (K <= 0) return 0.0;
  double denom = 1.0;
  for (Eigen::Index j = 1; j < K && j * p.step < p.length; ++j) {
    const Eigen::Index lag = j * p.step;
    const double rho = p.window.head(p.length - lag).dot(p.window.tail(p.length - lag)) / p.sum_w2;
    denom += 2.0 * (1.0 - static_cast<double>(j) / static_cast<double>(K)) * rho * rho;
  }
  return 2.0 * static_cast<double>(K) / denom;
}

/// Per-bin factor turning the sums over K segments into one-sided density/spectrum.
inline Eigen::VectorXd one_sided_scale(const SegmentPlan& p, double fs_hz, SpectralScaling s, Eigen::Index K) {
  const double base = 1.0 / ((s == SpectralScaling::density ? fs_hz * p.sum_w2 : p.sum_w * p.sum_w) * static_cast<double>(K));
  Eigen::VectorXd c = Eigen::VectorXd::Constant(p.bins, 2.0 * base);
  c(0) = base;
  if (p.nfft % 2 == 0) c(p.bins - 1) = base;
  return c;
}

inline Eigen::VectorXd bin_frequencies(const SegmentPlan& p, double fs_hz) {
  Eigen::VectorXd f(p.bins);
  for (Eigen::Index k = 0; k < p.bins; ++k) f(k) = static_cast<double>(k) * fs_hz / static_cast<double>(p.nfft);
  return f;
}

/// Detrend, taper and FFT of one channel segment. Holds the FFT plan and the work
/// buffer, so repeated calls allocate nothing.
class SegmentTransform {
 public:
  explicit SegmentTransform(const SegmentPlan& plan) : m_plan(plan), m_buffer(static_cast<std::size_t>(plan.nfft), 0.0) {
    m_fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  }

  /// Writes the nfft/2 + 1 bins of the transform of x(start : start + length - 1, c) to out.
  void operator()(const Eigen::Ref<const Eigen::MatrixXd>& x, Eigen::Index c, Eigen::Index start, std::complex<double>* out) {
    const SegmentPlan& p = m_plan;
    const double* src = x.data() + c * x.outerStride() + start;
    double offset = 0.0, slope = 0.0;
    if (p.detrend != Detrend::none) {
      double s0 = 0.0, s1 = 0.0;
      for (Eigen::Index n = 0; n < p.length; ++n) {
        s0 += src[n];
        s1 += p.ramp(n) * src[n];
      }
      offset = s0 / static_cast<double>(p.length);
      if (p.detrend == Detrend::linear && p.ramp_norm2 > 0.0) slope = s1 / p.ramp_norm2;
    }
    for (Eigen::Index n = 0; n < p.length; ++n)
      m_buffer[static_cast<std::size_t>(n)] = (src[n] - offset - slope * p.ramp(n)) * p.window(n);
    m_fft.fwd(out, m_buffer.data(), p.nfft);  // samples length..nfft-1 stay zero: zero padding
  }

 private:
  const SegmentPlan& m_plan;
  std::vector<double> m_buffer;
  Eigen::FFT<double> m_fft;
};

/// The one segment loop of every Welch-type estimate: for each segment of the
/// record, transforms every column of `a` and then of `b` exactly once into the
/// columns of `spectra` (bins x (a.cols() + b.cols()), allocated by the caller)
/// and calls visit(spectra). `b` may have no columns. Returns the number of segments.
template <class Visitor>
Eigen::Index for_each_segment(const Eigen::Ref<const Eigen::MatrixXd>& a, const Eigen::Ref<const Eigen::MatrixXd>& b,
                              const SegmentPlan& plan, SegmentTransform& transform, Eigen::MatrixXcd& spectra,
                              Visitor&& visit) {
  const Eigen::Index K = plan.segments_in(a.rows());
  for (Eigen::Index s = 0; s < K; ++s) {
    const Eigen::Index start = s * plan.step;
    for (Eigen::Index c = 0; c < a.cols(); ++c) transform(a, c, start, spectra.col(c).data());
    for (Eigen::Index c = 0; c < b.cols(); ++c) transform(b, c, start, spectra.col(a.cols() + c).data());
    visit(static_cast<const Eigen::MatrixXcd&>(spectra));
  }
  return K;
}

/// Running sums sum_segments conj(Z_i) Z_j for a list of channel pairs (i, j),
/// one column per pair, one row per bin.
struct PairSums {
  std::vector<std::pair<Eigen::Index, Eigen::Index>> pairs;
  Eigen::MatrixXcd sums;  ///< bins x pairs

  PairSums(std::vector<std::pair<Eigen::Index, Eigen::Index>> p, Eigen::Index bins)
      : pairs(std::move(p)), sums(Eigen::MatrixXcd::Zero(bins, static_cast<Eigen::Index>(pairs.size()))) {}

  void operator()(const Eigen::MatrixXcd& spectra) {
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto [i, j] = pairs[k];
      if (i == j)
        sums.col(static_cast<Eigen::Index>(k)).real() += spectra.col(i).cwiseAbs2();
      else
        sums.col(static_cast<Eigen::Index>(k)) += spectra.col(i).conjugate().cwiseProduct(spectra.col(j));
    }
  }
};

inline void check_finite(const Eigen::Ref<const Eigen::MatrixXd>& x, const std::string& who, const char* what) {
  if (!x.allFinite()) throw std::invalid_argument(who + ": need finite samples in " + what);
}

/// Auto-spectra of every column of x with a given plan (shared by welch_psd and periodogram).
inline PowerSpectrum auto_spectra(const Eigen::Ref<const Eigen::MatrixXd>& x, double fs_hz, const SegmentPlan& plan,
                                  SpectralScaling scaling) {
  PowerSpectrum out;
  out.nfft = plan.nfft;
  out.freq_hz = bin_frequencies(plan, fs_hz);
  out.psd = Eigen::MatrixXd::Zero(plan.bins, x.cols());
  SegmentTransform transform(plan);
  Eigen::MatrixXcd spectra(plan.bins, x.cols());
  const Eigen::MatrixXd none(x.rows(), 0);
  out.segments = for_each_segment(x, none, plan, transform, spectra, [&](const Eigen::MatrixXcd& z) {
    for (Eigen::Index c = 0; c < z.cols(); ++c) out.psd.col(c) += z.col(c).cwiseAbs2();
  });
  out.psd = one_sided_scale(plan, fs_hz, scaling, out.segments).asDiagonal() * out.psd;
  out.dof = welch_dof(plan, out.segments);
  return out;
}

}  // namespace detail

/// Purpose: one-sided PSD of every column of x (N x channels) by Welch's method.
/// Method, scaling and degrees of freedom: see the file comment.
/// Preconditions (std::invalid_argument): fs > 0 finite; nfft >= 8; 0 <= overlap < 1;
/// N >= 8; finite samples.
/// Numerical aspects: O(K channels nfft log nfft).
/// Example: `PowerSpectrum ps = welch_psd(data.experiments[0].u, 1.0 / data.Ts, {.nfft = 4096});`
template <class Derived>
PowerSpectrum welch_psd(const Eigen::MatrixBase<Derived>& x, double fs_hz, const WelchOptions& options = {}) {
  const Eigen::Ref<const Eigen::MatrixXd> xr(x.derived());
  const detail::SegmentPlan plan = detail::welch_plan(xr.rows(), fs_hz, options, "welch_psd");
  detail::check_finite(xr, "welch_psd", "x");
  return detail::auto_spectra(xr, fs_hz, plan, options.scaling);
}

/// Purpose: one-sided cross-spectral densities of every column of x (N x p) with
/// every column of y (N x q): csd[k](i, j) = S_{x_i y_j}(f_k), conjugate on x_i
/// (the convention of Bendat & Piersol's G_xy and of scipy.signal.csd(x_i, y_j)).
/// welch_csd(x, x) gives the full Hermitian spectral matrix, whose diagonal is welch_psd(x).
/// Method: file comment; one FFT per channel per segment, then one complex
/// multiply-add per bin per (i, j) pair.
/// Preconditions (std::invalid_argument): as welch_psd, and rows(x) == rows(y),
/// p >= 1, q >= 1.
/// Numerical aspects: O(K (p + q) nfft log nfft + K nfft p q / 2); memory
/// O(nfft p q) for the running sums.
template <class DerivedX, class DerivedY>
CrossSpectrum welch_csd(const Eigen::MatrixBase<DerivedX>& x, const Eigen::MatrixBase<DerivedY>& y, double fs_hz,
                        const WelchOptions& options = {}) {
  const std::string who = "welch_csd";
  const Eigen::Ref<const Eigen::MatrixXd> xr(x.derived());
  const Eigen::Ref<const Eigen::MatrixXd> yr(y.derived());
  if (xr.rows() != yr.rows())
    throw std::invalid_argument(who + ": need rows(x) == rows(y) (have " + std::to_string(xr.rows()) + " and " +
                                std::to_string(yr.rows()) + ")");
  if (xr.cols() < 1 || yr.cols() < 1) throw std::invalid_argument(who + ": need at least one column in x and in y");
  const detail::SegmentPlan plan = detail::welch_plan(xr.rows(), fs_hz, options, who);
  detail::check_finite(xr, who, "x");
  detail::check_finite(yr, who, "y");
  const Eigen::Index p = xr.cols(), q = yr.cols();
  std::vector<std::pair<Eigen::Index, Eigen::Index>> pairs;
  pairs.reserve(static_cast<std::size_t>(p * q));
  for (Eigen::Index j = 0; j < q; ++j)
    for (Eigen::Index i = 0; i < p; ++i) pairs.emplace_back(i, p + j);  // column-major (i, j) order
  detail::PairSums sums(std::move(pairs), plan.bins);
  detail::SegmentTransform transform(plan);
  Eigen::MatrixXcd spectra(plan.bins, p + q);
  CrossSpectrum out;
  out.nfft = plan.nfft;
  out.freq_hz = detail::bin_frequencies(plan, fs_hz);
  out.segments = detail::for_each_segment(xr, yr, plan, transform, spectra, sums);
  out.dof = detail::welch_dof(plan, out.segments);
  const Eigen::VectorXd scale = detail::one_sided_scale(plan, fs_hz, options.scaling, out.segments);
  out.csd.resize(static_cast<std::size_t>(plan.bins));
  for (Eigen::Index k = 0; k < plan.bins; ++k)
    out.csd[static_cast<std::size_t>(k)] = Eigen::Map<const Eigen::MatrixXcd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>(
                                               sums.sums.row(k).data(), p, q,
                                               Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(p * plan.bins, plan.bins)) *
                                           scale(k);
  return out;
}

}  // namespace sysid
