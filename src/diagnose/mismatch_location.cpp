// Mismatch location for `sysid diagnose`: the compiled part of
// include/sysid/diagnose/mismatch_location.hpp (method and references there).
#include <sysid/diagnose/mismatch_location.hpp>

#include <sysid/core/format_number.hpp>
#include <sysid/core/median.hpp>
#include <sysid/spectral/confidence.hpp>
#include <sysid/spectral/frf.hpp>
#include <sysid/spectral/welch.hpp>
#include <sysid/spectral/window.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

namespace detail {

// ---------------------------------------------------------------------------
// Beta and F distributions
// ---------------------------------------------------------------------------

double regularized_beta(double a, double b, double x) {
  if (!(a > 0.0) || !(b > 0.0) || !std::isfinite(a) || !std::isfinite(b))
    throw std::invalid_argument("regularized_beta: need 0 < a, b < infinity");
  if (!(x >= 0.0 && x <= 1.0)) throw std::invalid_argument("regularized_beta: need 0 <= x <= 1");
  if (x == 0.0) return 0.0;
  if (x == 1.0) return 1.0;
  // The continued fraction converges fast for x < (a+1)/(a+b+2); beyond, the
  // symmetric tail is computed directly (and then 1 - x is on the fast side).
  if (x > (a + 1.0) / (a + b + 2.0)) return 1.0 - regularized_beta(b, a, 1.0 - x);
  const double log_front = a * std::log(x) + b * std::log1p(-x) - (std::lgamma(a) + std::lgamma(b) - std::lgamma(a + b));
  const double front = std::exp(log_front) / a;
  // I_x = front / (1 + d1 / (1 + d2 / (1 + ...))) (A&S 26.5.8), evaluated forward by
  // the modified Lentz method with numerators 1, d1, d2, ... and denominators 1.
  constexpr double tiny = 1e-300;
  const double eps = std::numeric_limits<double>::epsilon();
  double f = tiny, C = tiny, D = 0.0;
  for (int j = 1; j < 200000; ++j) {
    double num;
    if (j == 1) {
      num = 1.0;
    } else {
      const int i = j - 1;  // index of d_i
      if (i % 2 == 1) {
        const double k = (i - 1) / 2;
        num = -(a + k) * (a + b + k) * x / ((a + 2.0 * k) * (a + 2.0 * k + 1.0));
      } else {
        const double k = i / 2;
        num = k * (b - k) * x / ((a + 2.0 * k - 1.0) * (a + 2.0 * k));
      }
    }
    D = 1.0 + num * D;
    if (std::abs(D) < tiny) D = tiny;
    C = 1.0 + num / C;
    if (std::abs(C) < tiny) C = tiny;
    D = 1.0 / D;
    const double delta = C * D;
    f *= delta;
    if (j > 1 && std::abs(delta - 1.0) < 4.0 * eps) return front * f;
  }
  throw std::runtime_error("regularized_beta: continued fraction did not converge (a = " + std::to_string(a) +
                           ", b = " + std::to_string(b) + ", x = " + std::to_string(x) + ")");
}

double beta_upper_quantile(double p, double a, double b) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("beta_upper_quantile: need 0 < p < 1");
  if (!(a > 0.0) || !(b > 0.0)) throw std::invalid_argument("beta_upper_quantile: need a, b > 0");
  if (a == 1.0) return 1.0 - std::pow(p, 1.0 / b);  // P(Beta(1, b) > c) = (1 - c)^b
  // P(Beta(a, b) > c) = I_{1-c}(b, a), computed in the tail (no 1 - (~1) cancellation);
  // it decreases in c, so bisection cannot fail.
  double lo = 0.0, hi = 1.0;
  for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
    const double mid = 0.5 * (lo + hi);
    (regularized_beta(b, a, 1.0 - mid) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double f_sf(double x, double d1, double d2) {
  if (!(d1 > 0.0) || !(d2 > 0.0)) throw std::invalid_argument("f_sf: need d1, d2 > 0");
  if (!(x >= 0.0)) throw std::invalid_argument("f_sf: need x >= 0");
  if (std::isinf(x)) return 0.0;
  // d1 X / (d1 X + d2) ~ Beta(d1/2, d2/2); its upper tail is I_{d2/(d2 + d1 x)}(d2/2, d1/2).
  return regularized_beta(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * x));
}

double f_upper_quantile(double p, double d1, double d2) {
  const double c = beta_upper_quantile(p, 0.5 * d1, 0.5 * d2);
  return c >= 1.0 ? std::numeric_limits<double>::infinity() : (d2 / d1) * c / (1.0 - c);
}

namespace {

// ---------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------

/// Main-lobe half-width of the window's spectrum in bins (number of cosine terms).
Eigen::Index mainlobe_halfwidth(WindowType w) {
  switch (w) {
    case WindowType::rectangular: return 1;
    case WindowType::hann:
    case WindowType::hamming: return 2;
    case WindowType::blackman_harris: return 4;
    case WindowType::flattop: return 5;
  }
  return 2;
}

/// rho_j^2, j = 0..J: squared correlation of the window's DFT at bin spacing j,
/// |sum_n w_n^2 e^{-2 pi i j n / L}|^2 / (sum_n w_n^2)^2 = correlation of |X_k|^2 and
/// |X_{k+j}|^2 for Gaussian noise (rho_0 = 1).
std::vector<double> window_bin_correlation(WindowType type, Eigen::Index L, Eigen::Index J) {
  const Eigen::VectorXd w = make_window(type, L);
  const Eigen::VectorXd w2 = w.cwiseAbs2();
  const double s = w2.sum();
  std::vector<double> rho2(static_cast<std::size_t>(J + 1), 0.0);
  for (Eigen::Index j = 0; j <= J; ++j) {
    std::complex<double> acc = 0.0;
    for (Eigen::Index n = 0; n < L; ++n)
      acc += w2(n) * std::polar(1.0, -2.0 * std::numbers::pi * static_cast<double>(j * n) / static_cast<double>(L));
    rho2[static_cast<std::size_t>(j)] = std::norm(acc) / (s * s);
  }
  return rho2;
}

/// q-quantile of a sorted vector with linear interpolation.
double sorted_quantile(const std::vector<double>& s, double q) {
  const double pos = q * static_cast<double>(s.size() - 1);
  const auto i = static_cast<std::size_t>(std::floor(pos));
  if (i + 1 >= s.size()) return s.back();
  const double t = pos - static_cast<double>(i);
  return s[i] + t * (s[i + 1] - s[i]);
}

Eigen::Index next_pow2(Eigen::Index n) {
  Eigen::Index p = 1;
  while (p < n) p *= 2;
  return p;
}

/// Critical value of z^2 for a two-sided t-test at level alpha with nu degrees of
/// freedom: t^2 ~ F(1, nu).
double t2_critical(double alpha, double nu) { return f_upper_quantile(alpha, 1.0, std::min(nu, 1e6)); }

// ---------------------------------------------------------------------------
// Variance of linear functionals of the residual (file comment of the header)
// ---------------------------------------------------------------------------

struct Moment {
  double value = 0.0;
  double dof = 0.0;  ///< Satterthwaite degrees of freedom of the estimate
};

/// Var(sum_t x_t r_t) = (1/M) sum_m fs S2(f_m) |X_m|^2 for a stationary residual of
/// one-sided density S (Welch bins), S2 its two-sided density linearly interpolated
/// to the M-point grid.
class FunctionalVariance {
 public:
  FunctionalVariance(const Eigen::VectorXd& S, double fs, double nu, const std::vector<double>& rho2, Eigen::Index N)
      : m_bins(S.size()), m_rho2(rho2) {
    const Eigen::Index L = 2 * (m_bins - 1);
    m_M = next_pow2(N + L / 2 + 1);
    const Eigen::Index half = m_M / 2 + 1;
    Eigen::VectorXd S2 = 0.5 * S;
    S2(0) = S(0);  // Welch's DC and Nyquist bins carry the two-sided density (c_k = 1)
    S2(m_bins - 1) = S(m_bins - 1);
    m_S2 = S2;
    m_nu_bin = Eigen::VectorXd::Constant(m_bins, nu);
    m_nu_bin(0) = 0.5 * nu;  // real-valued bins: half the degrees of freedom
    m_nu_bin(m_bins - 1) = 0.5 * nu;
    m_k0.resize(half);
    m_theta.resize(half);
    m_G.resize(half);
    for (Eigen::Index m = 0; m < half; ++m) {
      const double pos = static_cast<double>(m) * static_cast<double>(L) / static_cast<double>(m_M);
      Eigen::Index k0 = std::min<Eigen::Index>(static_cast<Eigen::Index>(std::floor(pos)), m_bins - 2);
      const double th = std::clamp(pos - static_cast<double>(k0), 0.0, 1.0);
      m_k0(m) = k0;
      m_theta(m) = th;
      m_G(m) = fs * ((1.0 - th) * S2(k0) + th * S2(k0 + 1));
    }
    m_fs = fs;
    m_fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
    m_buffer.assign(static_cast<std::size_t>(m_M), 0.0);
  }

  /// Half spectrum (M/2 + 1 bins) of x zero-padded to M.
  Eigen::VectorXcd transform(const Eigen::VectorXd& x) {
    std::fill(m_buffer.begin(), m_buffer.end(), 0.0);
    std::copy(x.data(), x.data() + x.size(), m_buffer.begin());
    Eigen::VectorXcd X(m_M / 2 + 1);
    m_fft.fwd(X.data(), m_buffer.data(), m_M);
    return X;
  }

  double covariance(const Eigen::VectorXcd& X, const Eigen::VectorXcd& Y) const {
    double s = 0.0;
    const Eigen::Index half = m_M / 2;
    for (Eigen::Index m = 0; m <= half; ++m) {
      const double mult = (m == 0 || m == half) ? 1.0 : 2.0;
      s += mult * m_G(m) * std::real(std::conj(X(m)) * Y(m));
    }
    return s / static_cast<double>(m_M);
  }

  /// Variance with Satterthwaite's degrees of freedom: the estimate is sum_k b_k,
  /// b_k the share of Welch bin k; Var(S_hat_k) = 2 S_k^2 / nu_k and adjacent bins
  /// correlate with rho_j^2.
  Moment variance(const Eigen::VectorXcd& X) const {
    Eigen::VectorXd b = Eigen::VectorXd::Zero(m_bins);
    const Eigen::Index half = m_M / 2;
    for (Eigen::Index m = 0; m <= half; ++m) {
      const double mult = (m == 0 || m == half) ? 1.0 : 2.0;
      const double p = mult * m_fs * std::norm(X(m)) / static_cast<double>(m_M);
      b(m_k0(m)) += p * (1.0 - m_theta(m)) * m_S2(m_k0(m));
      b(m_k0(m) + 1) += p * m_theta(m) * m_S2(m_k0(m) + 1);
    }
    Moment out;
    out.value = b.sum();
    double var = 0.0;
    const auto J = static_cast<Eigen::Index>(m_rho2.size()) - 1;
    for (Eigen::Index k = 0; k < m_bins; ++k) {
      if (b(k) == 0.0) continue;
      for (Eigen::Index j = std::max<Eigen::Index>(0, k - J); j <= std::min(m_bins - 1, k + J); ++j)
        var += 2.0 * b(k) * b(j) * m_rho2[static_cast<std::size_t>(std::abs(j - k))] / std::sqrt(m_nu_bin(k) * m_nu_bin(j));
    }
    out.dof = var > 0.0 ? 2.0 * out.value * out.value / var : 1e6;
    return out;
  }

 private:
  Eigen::Index m_bins = 0, m_M = 0;
  std::vector<double> m_rho2;
  Eigen::VectorXd m_S2, m_nu_bin, m_theta, m_G;
  Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1> m_k0;
  double m_fs = 1.0;
  Eigen::FFT<double> m_fft;
  std::vector<double> m_buffer;
};

/// Autocovariance R(j), j = 0..L/2, of a process with one-sided Welch density S
/// (bins = L/2 + 1): R(j) = df [S_0 + sum_{0<k<L/2} S_k cos(2 pi k j / L) + S_{L/2} (-1)^j].
Eigen::VectorXd autocovariance_from_psd(const Eigen::VectorXd& S, double fs) {
  const Eigen::Index bins = S.size(), L = 2 * (bins - 1);
  std::vector<double> s(static_cast<std::size_t>(L), 0.0);
  s[0] = S(0);
  s[static_cast<std::size_t>(L / 2)] = S(bins - 1);
  for (Eigen::Index k = 1; k < L / 2; ++k) s[static_cast<std::size_t>(k)] = s[static_cast<std::size_t>(L - k)] = 0.5 * S(k);
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  Eigen::VectorXcd F(bins);
  fft.fwd(F.data(), s.data(), L);
  return F.real() * (fs / static_cast<double>(L));
}

/// One-sided density of z = r^2 for Gaussian r: R_z(j) = 2 R(j)^2 transformed back
/// (a circular convolution of the non-negative S2 with itself, so non-negative).
Eigen::VectorXd square_process_psd(const Eigen::VectorXd& R, double fs) {
  const Eigen::Index bins = R.size(), L = 2 * (bins - 1);
  std::vector<double> z(static_cast<std::size_t>(L), 0.0);
  z[0] = 2.0 * R(0) * R(0);
  z[static_cast<std::size_t>(L / 2)] = 2.0 * R(bins - 1) * R(bins - 1);
  for (Eigen::Index j = 1; j < L / 2; ++j)
    z[static_cast<std::size_t>(j)] = z[static_cast<std::size_t>(L - j)] = 2.0 * R(j) * R(j);
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  Eigen::VectorXcd F(bins);
  fft.fwd(F.data(), z.data(), L);
  Eigen::VectorXd S = F.real().cwiseMax(0.0) / fs;  // two-sided
  S.segment(1, bins - 2) *= 2.0;                     // one-sided as Welch's layout
  return S;
}

// ---------------------------------------------------------------------------
// The per-output analyses
// ---------------------------------------------------------------------------

struct Common {
  double fs = 1.0, Ts = 1.0;
  Eigen::Index N = 0, m = 0, nfft = 0, bins = 0, g = 2;
  double nu = 0.0, alpha = 0.01, alpha_f = 0.01;
  std::vector<double> rho2;  // window bin correlations, j = 0..g+1
  const MismatchLocationOptions* o = nullptr;
};

std::vector<std::pair<Eigen::Index, Eigen::Index>> runs_of(const std::vector<Eigen::Index>& idx, Eigen::Index gap) {
  std::vector<std::pair<Eigen::Index, Eigen::Index>> runs;
  for (const Eigen::Index k : idx) {
    if (!runs.empty() && k - runs.back().second <= gap + 1) runs.back().second = k;
    else runs.emplace_back(k, k);
  }
  return runs;
}

std::string name_or(const std::vector<std::string>& names, Eigen::Index i, const char* prefix) {
  return i < static_cast<Eigen::Index>(names.size()) ? names[static_cast<std::size_t>(i)] : prefix + std::to_string(i + 1);
}

/// psi(x) - ln x and psi'(x) (digamma, trigamma) by the upward recurrence to x >= 6
/// and their asymptotic series (A&S 6.3.18, 6.4.12); ~1e-10 relative.
double digamma_minus_log(double x) {
  double acc = 0.0, z = x;
  while (z < 6.0) {
    acc -= 1.0 / z;
    z += 1.0;
  }
  const double z2 = 1.0 / (z * z);
  return acc + std::log(z / x) - 0.5 / z - z2 * (1.0 / 12.0 - z2 * (1.0 / 120.0 - z2 / 252.0));
}
double trigamma(double x) {
  double acc = 0.0, z = x;
  while (z < 6.0) {
    acc += 1.0 / (z * z);
    z += 1.0;
  }
  const double z2 = 1.0 / (z * z);
  return acc + 1.0 / z + 0.5 * z2 + z2 / z * (1.0 / 6.0 - z2 * (1.0 / 30.0 - z2 / 42.0));
}

struct LocalFloor {
  double floor = 0.0;  ///< estimate of the mean spectrum at the bin
  double dof = 1e6;    ///< equivalent chi-square degrees of freedom of that estimate
};

/// Floor of a Welch PSD at bin k from its neighbours: least-squares quadratic in
/// (j - k) fitted to ln S_j over |j - k| in (g, h], the window mirrored at DC and
/// Nyquist (the PSD of a real signal is even and periodic, so the mirrored window
/// stays centred on k and the fit sees the true curvature there). Two passes drop
/// neighbours outside [-5 s, +3 s] of the fit (other peaks; s^2 = psi'(nu/2) the
/// variance of ln(chi2_nu / nu)). ln S_hat is biased by E ln(chi2_nu/nu) =
/// psi(nu/2) - ln(nu/2), removed. The fitted value's variance w^T C w (w the fit's
/// weights, C the correlation of the used bins: rho_d^2 at spacing d, 1 for a bin
/// used twice through the mirror) gives its equivalent dof 2 / Var (the variance of
/// ln(chi2_d/d) is ~2/d).
LocalFloor local_floor(const Eigen::VectorXd& S, Eigen::Index k, Eigen::Index h, Eigen::Index g, double nu,
                       const std::vector<double>& rho2) {
  const Eigen::Index bins = S.size(), top = bins - 1;
  // Constant-Q near DC: a rational spectrum changes on the scale of its corner
  // frequency, which at low bins is a few bins, so the window shrinks to +-k/2
  // there (never below g + 3, the least that leaves 6 neighbours).
  h = std::min(h, std::max(g + 3, k / 2));
  std::vector<double> xs, ys;
  std::vector<Eigen::Index> idx;
  for (Eigen::Index j = k - h; j <= k + h; ++j) {
    if (std::abs(j - k) <= g) continue;
    Eigen::Index b = j < 0 ? -j : j;
    if (b > top) b = 2 * top - b;
    if (b <= 0 || b > top || !(S(b) > 0.0)) continue;
    xs.push_back(static_cast<double>(j - k) / static_cast<double>(h));
    ys.push_back(std::log(S(b)));
    idx.push_back(b);
  }
  LocalFloor out;
  const double s = std::sqrt(trigamma(0.5 * nu));
  const double log_bias = digamma_minus_log(0.5 * nu);
  std::vector<char> use(xs.size(), 1);
  Eigen::Vector3d coef = Eigen::Vector3d::Zero();
  Eigen::Matrix3d XtX_inv = Eigen::Matrix3d::Zero();
  for (int pass = 0; pass < 3; ++pass) {
    Eigen::Matrix3d XtX = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Xty = Eigen::Vector3d::Zero();
    std::size_t n = 0;
    for (std::size_t p = 0; p < xs.size(); ++p) {
      if (!use[p]) continue;
      const Eigen::Vector3d row(1.0, xs[p], xs[p] * xs[p]);
      XtX += row * row.transpose();
      Xty += row * ys[p];
      ++n;
    }
    if (n < 6) {
      out.floor = 0.0;  // too few neighbours: no floor, the bin is not tested
      return out;
    }
    XtX_inv = XtX.inverse();
    coef = XtX_inv * Xty;
    if (pass == 2) break;
    for (std::size_t p = 0; p < xs.size(); ++p) {
      const double e = ys[p] - (coef(0) + coef(1) * xs[p] + coef(2) * xs[p] * xs[p]);
      use[p] = (e < 3.0 * s && e > -5.0 * s) ? 1 : 0;
    }
  }
  out.floor = std::exp(coef(0) - log_bias);
  // Weights of the fitted value at x = 0: first row of (X^T X)^{-1} X^T.
  std::vector<double> w(xs.size(), 0.0);
  for (std::size_t p = 0; p < xs.size(); ++p)
    if (use[p]) w[p] = XtX_inv(0, 0) + XtX_inv(0, 1) * xs[p] + XtX_inv(0, 2) * xs[p] * xs[p];
  const auto J = static_cast<Eigen::Index>(rho2.size()) - 1;
  double v = 0.0;
  for (std::size_t p = 0; p < xs.size(); ++p) {
    if (!use[p]) continue;
    for (std::size_t q = 0; q < xs.size(); ++q) {
      if (!use[q]) continue;
      const Eigen::Index d = std::abs(idx[p] - idx[q]);
      if (d <= J) v += w[p] * w[q] * rho2[static_cast<std::size_t>(d)];
    }
  }
  v *= s * s;
  out.dof = v > 0.0 ? 2.0 / v : 1e6;
  return out;
}

void spectral_tests(const Common& c, const FrfResult& fr, Eigen::Index i, ChannelLocation& ch, const Eigen::VectorXd& S,
                    bool residual_zero, std::vector<std::string>& warnings) {
  const MismatchLocationOptions& o = *c.o;
  const Eigen::Index bins = c.bins, m = c.m;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double df = c.fs / static_cast<double>(c.nfft);
  ch.freq_hz = fr.freq_hz;
  ch.model_error_gain.resize(bins, m);
  ch.model_error_lower.resize(bins, m);
  ch.model_error_upper.resize(bins, m);
  ch.coherence.resize(bins, m);
  ch.joint_coherence = Eigen::VectorXd::Constant(bins, nan);
  for (Eigen::Index k = 0; k < bins; ++k) {
    const auto kb = static_cast<std::size_t>(k);
    for (Eigen::Index j = 0; j < m; ++j) {
      ch.model_error_gain(k, j) = std::abs(fr.H[kb](i, j));
      ch.model_error_lower(k, j) = fr.magnitude_lower[kb](i, j);
      ch.model_error_upper(k, j) = fr.magnitude_upper[kb](i, j);
      ch.coherence(k, j) = fr.coherence[kb](i, j);
    }
  }
  ch.residual_psd = S;
  ch.residual_floor = Eigen::VectorXd::Zero(bins);
  ch.residual_threshold = Eigen::VectorXd::Constant(bins, std::numeric_limits<double>::infinity());
  const auto in_band = [&](Eigen::Index k) { return fr.freq_hz(k) >= o.min_freq_hz && fr.freq_hz(k) <= o.max_freq_hz; };

  // --- 1. model-error FRF: joint coherence against Beta(m, n_d - m) ---
  const double nd = 0.5 * c.nu;
  std::vector<Eigen::Index> analysed;
  Eigen::VectorXd umax = fr.input_psd.colwise().maxCoeff().transpose();
  for (Eigen::Index k = 1; k + 1 < bins; ++k) {
    if (!in_band(k)) continue;
    const double jc = m == 1 ? ch.coherence(k, 0) : fr.multiple_coherence(k, i);
    bool powered = std::isfinite(jc);
    for (Eigen::Index j = 0; j < m && powered; ++j) powered = fr.input_psd(k, j) > 1e-12 * umax(j);
    if (!powered) continue;
    ch.joint_coherence(k) = jc;
    analysed.push_back(k);
  }
  double c_point = 1.0;
  const bool frf_testable = nd - static_cast<double>(m) >= 1.0 && !analysed.empty() && !residual_zero;
  if (!frf_testable) {
    if (!residual_zero)
      warnings.push_back(ch.output + ": model-error FRF not tested (" +
                         (analysed.empty() ? std::string("no excited bins in the band")
                                           : "n_d = " + format_number(nd) + " averages leave fewer than one for " +
                                                 std::to_string(m) + " inputs: lower nfft") +
                         ")");
    ch.coherence_threshold = 1.0;
  } else {
    const double b = nd - static_cast<double>(m), a = static_cast<double>(m);
    ch.coherence_threshold = beta_upper_quantile(c.alpha_f / static_cast<double>(analysed.size()), a, b);
    c_point = beta_upper_quantile(c.alpha, a, b);
    std::vector<Eigen::Index> sig;
    for (const Eigen::Index k : analysed)
      if (ch.joint_coherence(k) > ch.coherence_threshold) sig.push_back(k);
    for (const auto& [k0, k1] : runs_of(sig, o.band_merge_gap_bins)) {
      FalsifiedBand band;
      band.lo_hz = fr.freq_hz(k0);
      band.hi_hz = fr.freq_hz(k1);
      double best = -1.0;
      for (Eigen::Index k = k0; k <= k1; ++k) {
        if (!std::isfinite(ch.joint_coherence(k))) continue;
        for (Eigen::Index j = 0; j < m; ++j) {
          const double contribution = ch.model_error_gain(k, j) * ch.model_error_gain(k, j) * fr.input_psd(k, j);
          if (contribution > best) {
            best = contribution;
            band.peak_hz = fr.freq_hz(k);
            band.peak_gain = ch.model_error_gain(k, j);
            band.peak_coherence = ch.joint_coherence(k);
            band.input = j;
            band.input_name = name_or(o.input_names, j, "u");
          }
        }
      }
      ch.bands.push_back(band);
    }
  }

  // --- 2. narrow-band residual peaks ---
  if (residual_zero) return;
  const Eigen::Index last = bins - 2;
  // Bins within the main lobe of DC are excluded: leakage of slow drift lands there.
  std::vector<Eigen::Index> peak_bins;
  for (Eigen::Index k = c.g + 1; k <= last; ++k)
    if (in_band(k)) peak_bins.push_back(k);
  const double alpha_bin = c.alpha_f / static_cast<double>(std::max<std::size_t>(1, peak_bins.size()));
  // Interior bins share the fit design, so their floors share the dof: the F quantile
  // is memoised on the dof rounded to 0.1 % (the quantile changes far less).
  std::map<long, double> quantile_cache;
  for (Eigen::Index k = 1; k <= last; ++k) {
    const LocalFloor lf = local_floor(S, k, o.floor_halfwidth_bins, c.g, c.nu, c.rho2);
    ch.residual_floor(k) = lf.floor;
    if (!(in_band(k) && k > c.g && lf.floor > 0.0)) continue;
    const long key = std::lround(1000.0 * std::log(lf.dof));
    auto it = quantile_cache.find(key);
    if (it == quantile_cache.end())
      it = quantile_cache.emplace(key, f_upper_quantile(alpha_bin, c.nu, std::exp(static_cast<double>(key) / 1000.0))).first;
    ch.residual_threshold(k) = lf.floor * it->second;
  }
  ch.residual_floor(0) = ch.residual_floor(1);
  ch.residual_floor(bins - 1) = ch.residual_floor(last);
  const Eigen::Index g = c.g;
  std::vector<Eigen::Index> sig;
  for (const Eigen::Index k : peak_bins)
    if (S(k) > ch.residual_threshold(k)) sig.push_back(k);
  for (const auto& [k0, k1] : runs_of(sig, g)) {
    Eigen::Index kp = k0;
    for (Eigen::Index k = k0; k <= k1; ++k)
      if (S(k) > S(kp)) kp = k;
    // Coherent with the inputs (even pointwise), or inside a falsified band: that is
    // model error, not a disturbance.
    if (std::isfinite(ch.joint_coherence(kp)) && ch.joint_coherence(kp) > c_point) continue;
    bool in_falsified = false;
    for (const auto& band : ch.bands)
      if (fr.freq_hz(kp) >= band.lo_hz - static_cast<double>(g) * df && fr.freq_hz(kp) <= band.hi_hz + static_cast<double>(g) * df)
        in_falsified = true;
    if (in_falsified) continue;
    ResidualPeak p;
    const double tiny = 1e-300;
    const double la = std::log(std::max(S(kp - 1), tiny)), lb = std::log(S(kp)), lc = std::log(std::max(S(kp + 1), tiny));
    const double den = la - 2.0 * lb + lc;
    const double delta = den < 0.0 ? std::clamp(0.5 * (la - lc) / den, -0.5, 0.5) : 0.0;
    p.freq_hz = (static_cast<double>(kp) + delta) * df;
    const double floor = ch.residual_floor(kp);
    double power = 0.0;
    for (Eigen::Index j = std::max<Eigen::Index>(0, kp - g - 1); j <= std::min(bins - 1, kp + g + 1); ++j)
      power += (S(j) - floor) * df;
    p.amplitude = std::sqrt(2.0 * std::max(0.0, power));
    p.prominence_db = 10.0 * std::log10(S(kp) / floor);
    ch.peaks.push_back(p);
  }
}

void time_window_test(const Common& c, const Eigen::VectorXd& rc, const Eigen::VectorXd& R, ChannelLocation& ch) {
  const Eigen::Index N = c.N, W = c.o->time_windows;
  const Eigen::Index maxlag = R.size() - 1;
  std::vector<double> ms(static_cast<std::size_t>(W)), nu_w(static_cast<std::size_t>(W));
  ch.windows.resize(static_cast<std::size_t>(W));
  for (Eigen::Index b = 0; b < W; ++b) {
    const Eigen::Index s0 = b * N / W, s1 = (b + 1) * N / W, n = s1 - s0;
    ms[static_cast<std::size_t>(b)] = rc.segment(s0, n).squaredNorm() / static_cast<double>(n);
    // tau = sum_{|j|<n} rho(j)^2 (1 - |j|/n): Var(mean square) = 2 R(0)^2 tau / n.
    double tau = 1.0;
    for (Eigen::Index j = 1; j < std::min(n, maxlag + 1); ++j) {
      const double rho = R(j) / R(0);
      tau += 2.0 * rho * rho * (1.0 - static_cast<double>(j) / static_cast<double>(n));
    }
    nu_w[static_cast<std::size_t>(b)] = static_cast<double>(n) / tau;
    ch.windows[static_cast<std::size_t>(b)].t0_s = static_cast<double>(s0) * c.Ts;
    ch.windows[static_cast<std::size_t>(b)].t1_s = static_cast<double>(s1) * c.Ts;
  }
  const double nu_win = *std::min_element(nu_w.begin(), nu_w.end());
  const double floor = median(ms) / (chi_square_quantile(0.5, nu_win) / nu_win);
  const double nu_floor = nu_win * static_cast<double>(W) * 2.0 / std::numbers::pi;
  ch.window_threshold = f_upper_quantile(c.alpha_f / static_cast<double>(W), nu_win, nu_floor);
  for (Eigen::Index b = 0; b < W; ++b) {
    auto& w = ch.windows[static_cast<std::size_t>(b)];
    w.energy_ratio = floor > 0.0 ? ms[static_cast<std::size_t>(b)] / floor : 0.0;
    w.flagged = floor > 0.0 && w.energy_ratio > ch.window_threshold;
  }
}

void amplitude_test(const Common& c, const Eigen::VectorXd& y, const Eigen::VectorXd& yn, const Eigen::VectorXd& rc,
                    FunctionalVariance& fv, ChannelLocation& ch, std::vector<std::string>& warnings) {
  const MismatchLocationOptions& o = *c.o;
  const Eigen::Index N = c.N;
  const double mean = yn.mean();
  const Eigen::VectorXd a = (yn.array() - mean).abs().matrix();
  std::vector<double> sorted(a.data(), a.data() + N);
  std::sort(sorted.begin(), sorted.end());
  const double q_lo = sorted_quantile(sorted, o.low_amplitude_quantile);
  const double q_hi = sorted_quantile(sorted, o.high_amplitude_quantile);
  // Weights of the LS slope with intercept in a set: w_t = (yn_t - mean_S) / Sxx_S on S.
  const auto slope_weights = [&](bool high, double& rms) -> Eigen::VectorXd {
    Eigen::VectorXd w = Eigen::VectorXd::Zero(N);
    double sx = 0.0, e2 = 0.0;
    Eigen::Index n = 0;
    for (Eigen::Index t = 0; t < N; ++t)
      if (high ? a(t) >= q_hi : a(t) <= q_lo) {
        sx += yn(t);
        e2 += rc(t) * rc(t);
        ++n;
      }
    if (n < 10) return Eigen::VectorXd();
    const double xbar = sx / static_cast<double>(n);
    double sxx = 0.0;
    for (Eigen::Index t = 0; t < N; ++t)
      if (high ? a(t) >= q_hi : a(t) <= q_lo) sxx += (yn(t) - xbar) * (yn(t) - xbar);
    if (!(sxx > 0.0)) return Eigen::VectorXd();
    for (Eigen::Index t = 0; t < N; ++t)
      if (high ? a(t) >= q_hi : a(t) <= q_lo) w(t) = (yn(t) - xbar) / sxx;
    rms = std::sqrt(e2 / static_cast<double>(n));
    return w;
  };
  double rms_lo = 0.0, rms_hi = 0.0;
  const Eigen::VectorXd wl = slope_weights(false, rms_lo), wh = slope_weights(true, rms_hi);
  AmplitudeDependence& A = ch.amplitude;
  if (wl.size() == 0 || wh.size() == 0) {
    warnings.push_back(ch.output + ": amplitude dependence not tested (the nominal output has no spread in the low or high set)");
    return;
  }
  A.tested = true;
  A.gain_low = wl.dot(y);
  A.gain_high = wh.dot(y);
  A.gain_low_se = std::sqrt(fv.variance(fv.transform(wl)).value);
  A.gain_high_se = std::sqrt(fv.variance(fv.transform(wh)).value);
  A.rms_ratio = rms_lo > 0.0 ? rms_hi / rms_lo : std::numeric_limits<double>::infinity();
  const Moment vd = fv.variance(fv.transform(wh - wl));
  A.z = vd.value > 0.0 ? (A.gain_high - A.gain_low) / std::sqrt(vd.value) : 0.0;
  A.flagged = A.z * A.z > t2_critical(c.alpha_f, vd.dof);
}

void reversal_test(const Common& c, const Eigen::VectorXd& yn, const Eigen::VectorXd& rc, FunctionalVariance& fv,
                   FunctionalVariance& fv2, ChannelLocation& ch, std::vector<std::string>& warnings) {
  const MismatchLocationOptions& o = *c.o;
  const Eigen::Index N = c.N;
  ReversalDependence& Rv = ch.reversal;
  // Central-difference velocity (one-sided at the ends; Ts omitted: only the sign is used).
  Eigen::VectorXd v(N);
  v(0) = yn(1) - yn(0);
  v(N - 1) = yn(N - 1) - yn(N - 2);
  for (Eigen::Index t = 1; t + 1 < N; ++t) v(t) = 0.5 * (yn(t + 1) - yn(t - 1));
  // Centred moving average (truncated at the ends) through prefix sums.
  const Eigen::Index s = o.velocity_smoothing;
  Eigen::VectorXd prefix(N + 1);
  prefix(0) = 0.0;
  for (Eigen::Index t = 0; t < N; ++t) prefix(t + 1) = prefix(t) + v(t);
  Eigen::VectorXd vs(N);
  for (Eigen::Index t = 0; t < N; ++t) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, t - (s - 1) / 2), hi = std::min(N, t + s / 2 + 1);
    vs(t) = (prefix(hi) - prefix(lo)) / static_cast<double>(hi - lo);
  }
  Eigen::VectorXd sg(N);
  double current = 0.0;
  for (Eigen::Index t = 0; t < N && current == 0.0; ++t) current = vs(t) > 0.0 ? 1.0 : (vs(t) < 0.0 ? -1.0 : 0.0);
  std::vector<Eigen::Index> rev;
  for (Eigen::Index t = 0; t < N; ++t) {
    const double sgn = vs(t) > 0.0 ? 1.0 : (vs(t) < 0.0 ? -1.0 : current);
    if (t > 0 && sgn != current) rev.push_back(t);
    current = sgn;
    sg(t) = sgn;
  }
  Rv.reversals = static_cast<Eigen::Index>(rev.size());
  if (rev.size() < 2 || current == 0.0) {
    warnings.push_back(ch.output + ": reversal dependence not tested (fewer than 2 velocity reversals of the nominal output)");
    return;
  }
  Eigen::Index k = o.reversal_halfwidth;
  if (k == 0) {
    std::vector<double> spacing;
    for (std::size_t q = 1; q < rev.size(); ++q) spacing.push_back(static_cast<double>(rev[q] - rev[q - 1]));
    k = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::lround(0.1 * median(spacing))));
  }
  Rv.halfwidth = k;
  std::vector<char> near(static_cast<std::size_t>(N), 0);
  for (const Eigen::Index t : rev)
    for (Eigen::Index q = std::max<Eigen::Index>(0, t - k); q < std::min(N, t + k); ++q) near[static_cast<std::size_t>(q)] = 1;
  const auto n_near = static_cast<Eigen::Index>(std::count(near.begin(), near.end(), 1));
  const Eigen::Index n_far = N - n_near;
  if (n_near < 10 || n_far < 10) {
    warnings.push_back(ch.output + ": reversal dependence not tested (near-reversal set of " + std::to_string(n_near) +
                       " samples, elsewhere " + std::to_string(n_far) + ": need >= 10 each)");
    return;
  }
  Rv.tested = true;
  // Partial out what is linear in the nominal motion: regress r on [1, y_nom, v, sign(v)].
  // For a linear mismatch with Gaussian signals E[r | y_nom, v] is linear, so the
  // sign(v) coefficient and the energy of r - (linear part) near reversals are then
  // null (Bussgang: the raw correlation of r with sign(v) is not: it is proportional
  // to that of r with v).
  Eigen::MatrixXd X(N, 4);
  X.col(0).setOnes();
  X.col(1) = yn.array() - yn.mean();
  X.col(2) = vs / std::max(1e-300, std::sqrt(vs.squaredNorm() / static_cast<double>(N)));
  X.col(3) = sg;
  const Eigen::LDLT<Eigen::MatrixXd> gram(X.transpose() * X);
  if (gram.info() != Eigen::Success || !(gram.vectorD().minCoeff() > 1e-9 * gram.vectorD().maxCoeff())) {
    Rv.tested = false;
    warnings.push_back(ch.output + ": reversal dependence not tested (sign(v) nearly collinear with y_nom and v)");
    return;
  }
  const Eigen::MatrixXd XtX_inv = gram.solve(Eigen::MatrixXd::Identity(4, 4));
  const Eigen::VectorXd ws = X * XtX_inv.col(3);  // sign coefficient = ws^T r
  const Eigen::MatrixXd X3 = X.leftCols(3);
  const Eigen::VectorXd r_lin = rc - X3 * (X3.transpose() * X3).ldlt().solve(X3.transpose() * rc);
  Eigen::VectorXd x(N);
  double ms_near = 0.0, ms_far = 0.0;
  for (Eigen::Index t = 0; t < N; ++t) {
    const bool nr = near[static_cast<std::size_t>(t)] != 0;
    x(t) = nr ? 1.0 / static_cast<double>(n_near) : -1.0 / static_cast<double>(n_far);
    (nr ? ms_near : ms_far) += r_lin(t) * r_lin(t);
  }
  ms_near /= static_cast<double>(n_near);
  ms_far /= static_cast<double>(n_far);
  Rv.energy_ratio = ms_far > 0.0 ? ms_near / ms_far : std::numeric_limits<double>::infinity();
  // Var of the difference of mean squares: kernel 2 R(k)^2 (Gaussian fourth moments).
  // Its estimate pools many Welch bins; nu is a conservative count of its degrees of freedom.
  const double var_e = fv2.variance(fv2.transform(x)).value;
  Rv.energy_z = var_e > 0.0 ? (ms_near - ms_far) / std::sqrt(var_e) : 0.0;
  const Eigen::VectorXd sc = (sg.array() - sg.mean()).matrix();
  const double denom = std::sqrt(sc.squaredNorm() * rc.squaredNorm());
  Rv.sign_correlation = denom > 0.0 ? sc.dot(rc) / denom : 0.0;
  Rv.sign_level = ws.dot(rc);
  const Moment vs_m = fv.variance(fv.transform(ws));
  Rv.sign_z = vs_m.value > 0.0 ? Rv.sign_level / std::sqrt(vs_m.value) : 0.0;
  Rv.flagged = Rv.energy_z * Rv.energy_z > t2_critical(0.5 * c.alpha_f, c.nu) ||
               Rv.sign_z * Rv.sign_z > t2_critical(0.5 * c.alpha_f, vs_m.dof);
}

void position_test(const Common& c, const Eigen::VectorXd& yn, const Eigen::VectorXd& r, FunctionalVariance& fv,
                   ChannelLocation& ch) {
  const Eigen::Index N = c.N, B = c.o->position_bins;
  PositionDependence& P = ch.position;
  std::vector<Eigen::Index> order(static_cast<std::size_t>(N));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return yn(a) < yn(b); });
  // LS line r ~ a + b yn over all samples; its projection enters every bin's weights.
  // Centred regressor: the normal equations stay well conditioned for any offset of y_nom.
  const double yn_mean = yn.mean();
  Eigen::MatrixXd X(N, 2);
  X.col(0).setOnes();
  X.col(1) = yn.array() - yn_mean;
  const Eigen::Matrix2d XtX_inv = (X.transpose() * X).inverse();
  const Eigen::Vector2d coef = XtX_inv * (X.transpose() * r);
  const Eigen::VectorXd r_detr = r - X * coef;
  P.bin_centres.resize(B);
  P.bin_means.resize(B);
  P.bin_means_detrended.resize(B);
  std::vector<Eigen::VectorXcd> Wf;
  Wf.reserve(static_cast<std::size_t>(B));
  double nu_min = 1e6;
  for (Eigen::Index b = 0; b < B; ++b) {
    const Eigen::Index s0 = b * N / B, s1 = (b + 1) * N / B, n = s1 - s0;
    Eigen::VectorXd w = Eigen::VectorXd::Zero(N);
    double sx = 0.0, sr = 0.0, sd = 0.0;
    for (Eigen::Index q = s0; q < s1; ++q) {
      const Eigen::Index t = order[static_cast<std::size_t>(q)];
      w(t) = 1.0 / static_cast<double>(n);
      sx += yn(t);
      sr += r(t);
      sd += r_detr(t);
    }
    P.bin_centres(b) = sx / static_cast<double>(n);
    P.bin_means(b) = sr / static_cast<double>(n);
    P.bin_means_detrended(b) = sd / static_cast<double>(n);
    // Detrended bin mean = sum_t (w_t - (X (X^T X)^{-1} X^T w)_t) r_t.
    const Eigen::Vector2d Xtw(1.0, P.bin_centres(b) - yn_mean);
    w -= X * (XtX_inv * Xtw);
    Wf.push_back(fv.transform(w));
    nu_min = std::min(nu_min, fv.variance(Wf.back()).dof);
  }
  Eigen::MatrixXd C(B, B);
  for (Eigen::Index a = 0; a < B; ++a)
    for (Eigen::Index b = a; b < B; ++b)
      C(a, b) = C(b, a) = fv.covariance(Wf[static_cast<std::size_t>(a)], Wf[static_cast<std::size_t>(b)]);
  // The detrended means obey two linear constraints, so C has rank B - 2: pseudo-inverse.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(C);
  const Eigen::VectorXd lam = eig.eigenvalues();
  const double lmax = lam.maxCoeff();
  if (!(lmax > 0.0)) return;
  double Q = 0.0;
  Eigen::Index rank = 0;
  for (Eigen::Index q = 0; q < B; ++q)
    if (lam(q) > 1e-9 * lmax) {
      const double proj = eig.eigenvectors().col(q).dot(P.bin_means_detrended);
      Q += proj * proj / lam(q);
      ++rank;
    }
  if (rank == 0) return;
  P.tested = true;
  P.f_statistic = Q / static_cast<double>(rank);
  P.p_value = f_sf(P.f_statistic, static_cast<double>(rank), std::min(nu_min, 1e6));
  P.flagged = P.p_value < c.alpha_f;
}

void offset_test(const Common& c, const Eigen::VectorXd& r, FunctionalVariance& fv, ChannelLocation& ch) {
  const Eigen::Index N = c.N;
  OffsetDrift& O = ch.offset;
  const Eigen::VectorXd wm = Eigen::VectorXd::Constant(N, 1.0 / static_cast<double>(N));
  Eigen::VectorXd tc(N);
  for (Eigen::Index t = 0; t < N; ++t) tc(t) = (static_cast<double>(t) - 0.5 * static_cast<double>(N - 1)) * c.Ts;
  const Eigen::VectorXd ws = tc / tc.squaredNorm();
  O.offset = r.mean();
  O.slope_per_s = ws.dot(r);
  const Moment vm = fv.variance(fv.transform(wm)), vs = fv.variance(fv.transform(ws));
  O.offset_se = std::sqrt(vm.value);
  O.slope_se = std::sqrt(vs.value);
  const double zm = O.offset_se > 0.0 ? O.offset / O.offset_se : 0.0;
  const double zs = O.slope_se > 0.0 ? O.slope_per_s / O.slope_se : 0.0;
  O.flagged = zm * zm > t2_critical(0.5 * c.alpha_f, vm.dof) || zs * zs > t2_critical(0.5 * c.alpha_f, vs.dof);
}

/// f - mean(f) when f varies beyond round-off of its own size, else empty (a
/// constant function: a binary input's square).
Eigen::VectorXd centred_if_varying(const Eigen::VectorXd& f) {
  Eigen::VectorXd centred = f.array() - f.mean();
  if (!(centred.cwiseAbs().maxCoeff() > 1e-9 * f.cwiseAbs().maxCoeff())) return {};
  return centred;
}

/// The even functions of the inputs test 8 extends them with, centred: with
/// d_j = u_j - mean(u_j) (even about the operating point, so that an input with
/// an offset does not make |u_j| a copy of u_j), d_j^2 and |d_j| per input while
/// the averages allow n_d - m - p >= 1, else d_j^2 only (or nothing). A constant
/// function is left out, and |d_j| when it is proportional to d_j^2 (a ternary
/// input).
Eigen::MatrixXd even_input_functions(const Eigen::MatrixXd& u, double nd) {
  const Eigen::Index N = u.rows(), m = u.cols();
  std::vector<Eigen::VectorXd> squares, magnitudes;
  for (Eigen::Index j = 0; j < m; ++j) {
    const Eigen::VectorXd d = u.col(j).array() - u.col(j).mean();
    Eigen::VectorXd square = centred_if_varying(d.array().square().matrix());
    Eigen::VectorXd magnitude = centred_if_varying(d.cwiseAbs());
    // |d| is constant when d^2 is, so a kept magnitude always has a square beside it.
    if (square.size() == 0) continue;
    const bool proportional =
        magnitude.size() == 0 || std::abs(square.dot(magnitude)) >= (1.0 - 1e-9) * square.norm() * magnitude.norm();
    squares.push_back(std::move(square));
    if (!proportional) magnitudes.push_back(std::move(magnitude));
  }
  const auto room = [&](std::size_t p) { return nd - static_cast<double>(m) - static_cast<double>(p) >= 1.0; };
  if (!room(squares.size() + magnitudes.size())) magnitudes.clear();
  if (!room(squares.size())) squares.clear();
  Eigen::MatrixXd f(N, static_cast<Eigen::Index>(squares.size() + magnitudes.size()));
  Eigen::Index col = 0;
  for (const auto* set : {&squares, &magnitudes})
    for (const auto& v : *set) f.col(col++) = v;
  return f;
}

/// Test 8 for output i: partial multiple coherence of r_i with the p even functions
/// given u, from the H1 fits on u (test 1's joint coherence, in ch) and on [u f].
void asymmetry_test(const Common& c, const FrfResult& extended, Eigen::Index p, Eigen::Index i, ChannelLocation& ch) {
  AsymmetryDependence& A = ch.asymmetry;
  A.partial_coherence = Eigen::VectorXd::Constant(c.bins, std::numeric_limits<double>::quiet_NaN());
  if (p == 0) return;
  std::vector<Eigen::Index> analysed;
  for (Eigen::Index k = 1; k + 1 < c.bins; ++k) {
    const double base = ch.joint_coherence(k), joint = extended.multiple_coherence(k, i);
    if (!std::isfinite(base) || !std::isfinite(joint) || extended.ill_conditioned[static_cast<std::size_t>(k)] || !(base < 1.0))
      continue;
    A.partial_coherence(k) = std::max(0.0, (joint - base) / (1.0 - base));
    analysed.push_back(k);
  }
  if (analysed.empty()) return;
  A.tested = true;
  A.regressors = static_cast<int>(p);
  const double nd = 0.5 * c.nu;
  A.threshold = beta_upper_quantile(c.alpha_f / static_cast<double>(analysed.size()), static_cast<double>(p),
                                    nd - static_cast<double>(c.m + p));
  for (const Eigen::Index k : analysed)
    if (A.partial_coherence(k) > A.peak_partial_coherence) {
      A.peak_partial_coherence = A.partial_coherence(k);
      A.peak_hz = extended.freq_hz(k);
    }
  A.flagged = A.peak_partial_coherence > A.threshold;
}

void check_options(const MismatchLocationOptions& o, Eigen::Index N) {
  const std::string who = "locate_mismatch";
  if (!(o.significance > 0.0 && o.significance < 1.0)) throw std::invalid_argument(who + ": need 0 < significance < 1");
  if (!(o.overlap >= 0.0 && o.overlap < 1.0)) throw std::invalid_argument(who + ": need 0 <= overlap < 1");
  if (o.nfft != 0 && o.nfft < 16) throw std::invalid_argument(who + ": need nfft == 0 (auto) or nfft >= 16");
  if (!(o.min_freq_hz < o.max_freq_hz) || !(o.min_freq_hz >= 0.0))
    throw std::invalid_argument(who + ": need 0 <= min_freq_hz < max_freq_hz");
  if (o.band_merge_gap_bins < 0) throw std::invalid_argument(who + ": need band_merge_gap_bins >= 0");
  if (o.floor_halfwidth_bins < mainlobe_halfwidth(o.window) + 3)
    throw std::invalid_argument(who + ": need floor_halfwidth_bins >= main-lobe half-width + 3 (= " +
                                std::to_string(mainlobe_halfwidth(o.window) + 3) + ")");
  if (o.time_windows < 3) throw std::invalid_argument(who + ": need time_windows >= 3");
  if (N / o.time_windows < 8) throw std::invalid_argument(who + ": need N / time_windows >= 8");
  if (!(o.low_amplitude_quantile > 0.0 && o.low_amplitude_quantile < o.high_amplitude_quantile &&
        o.high_amplitude_quantile < 1.0))
    throw std::invalid_argument(who + ": need 0 < low_amplitude_quantile < high_amplitude_quantile < 1");
  if (o.velocity_smoothing < 1) throw std::invalid_argument(who + ": need velocity_smoothing >= 1");
  if (o.reversal_halfwidth < 0) throw std::invalid_argument(who + ": need reversal_halfwidth >= 0");
  if (o.position_bins < 3) throw std::invalid_argument(who + ": need position_bins >= 3");
  if (N / o.position_bins < 8) throw std::invalid_argument(who + ": need N / position_bins >= 8");
}

}  // namespace

MismatchLocation locate_mismatch_impl(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y, const Eigen::MatrixXd& residual,
                                      const Eigen::MatrixXd& y_nominal, double Ts, const MismatchLocationOptions& o) {
  const std::string who = "locate_mismatch";
  const Eigen::Index N = y.rows(), l = y.cols(), m = u.cols();
  if (u.rows() != N || residual.rows() != N || y_nominal.rows() != N)
    throw std::invalid_argument(who + ": need rows(u) == rows(y) == rows(residual) == rows(y_nominal) (have " +
                                std::to_string(u.rows()) + ", " + std::to_string(N) + ", " + std::to_string(residual.rows()) +
                                ", " + std::to_string(y_nominal.rows()) + ")");
  if (l < 1 || residual.cols() != l || y_nominal.cols() != l)
    throw std::invalid_argument(who + ": need cols(y) == cols(residual) == cols(y_nominal) >= 1");
  if (m < 1) throw std::invalid_argument(who + ": need cols(u) >= 1");
  if (!(Ts > 0.0) || !std::isfinite(Ts)) throw std::invalid_argument(who + ": need 0 < Ts < infinity");
  if (!u.allFinite() || !y.allFinite() || !residual.allFinite() || !y_nominal.allFinite())
    throw std::invalid_argument(who + ": need finite samples in u, y, residual and y_nominal");
  check_options(o, N);
  Eigen::Index nfft = o.nfft;
  if (nfft == 0) {
    nfft = 1;
    while (nfft * 2 <= N / 8 && nfft < 4096) nfft *= 2;
    if (nfft < 16) throw std::invalid_argument(who + ": need N >= 128 samples (have " + std::to_string(N) + ")");
  }
  if (N < 8 * nfft)
    throw std::invalid_argument(who + ": need N >= 8 nfft (N = " + std::to_string(N) + ", nfft = " + std::to_string(nfft) + ")");

  MismatchLocation out;
  Common c;
  c.fs = 1.0 / Ts;
  c.Ts = Ts;
  c.N = N;
  c.m = m;
  c.nfft = nfft;
  c.bins = nfft / 2 + 1;
  c.g = mainlobe_halfwidth(o.window);
  c.alpha = o.significance;
  constexpr int kFamilies = 8;
  c.alpha_f = o.significance / static_cast<double>(kFamilies * l);
  c.rho2 = window_bin_correlation(o.window, nfft, c.g + 1);
  c.o = &o;

  const double scale = y.cwiseAbs().maxCoeff() + y_nominal.cwiseAbs().maxCoeff();
  if ((residual - (y - y_nominal)).cwiseAbs().maxCoeff() > 1e-6 * std::max(scale, 1e-300))
    out.warnings.push_back("residual differs from y - y_nominal: the gains of the amplitude test use y and y_nominal");

  const Eigen::MatrixXd rc = residual.rowwise() - residual.colwise().mean();
  const WelchOptions wo{.nfft = nfft, .overlap = o.overlap, .window = o.window, .detrend = Detrend::mean,
                        .scaling = SpectralScaling::density};
  FrfOptions fo;
  fo.welch = wo;
  fo.confidence = 1.0 - o.significance;
  const FrfResult fr = frf(u, rc, c.fs, fo);
  for (const auto& w : fr.warnings)
    if (w.rfind("input cross-spectral matrix ill-conditioned", 0) == 0) out.warnings.push_back("model-error FRF: " + w);
  // The residual's own spectrum without per-segment detrending (the mean was removed
  // globally): its DC bin carries the slow correlation the mean-type tests need.
  WelchOptions wn = wo;
  wn.detrend = Detrend::none;
  const PowerSpectrum ps = welch_psd(rc, c.fs, wn);
  c.nu = ps.dof;
  out.nfft = nfft;
  out.segments = ps.segments;
  out.dof = ps.dof;
  out.family_level = c.alpha_f;
  // Test 8's inputs: u extended by even functions of it, one H1 fit for all outputs.
  const Eigen::MatrixXd even = even_input_functions(u, 0.5 * c.nu);
  FrfResult extended;
  if (even.cols() > 0) {
    Eigen::MatrixXd u_extended(N, m + even.cols());
    u_extended << u, even;
    extended = frf(u_extended, rc, c.fs, fo);
  }

  for (Eigen::Index i = 0; i < l; ++i) {
    ChannelLocation ch;
    ch.output = name_or(o.output_names, i, "y");
    const Eigen::VectorXd S = ps.psd.col(i);
    const Eigen::VectorXd rci = rc.col(i);
    ch.residual_rms = std::sqrt(rci.squaredNorm() / static_cast<double>(N));
    const bool residual_zero = !(ch.residual_rms > 0.0) || !(S.maxCoeff() > 0.0);
    if (residual_zero) out.warnings.push_back(ch.output + ": the residual is constant: nothing to locate");
    spectral_tests(c, fr, i, ch, S, residual_zero, out.warnings);
    if (!residual_zero) {
      asymmetry_test(c, extended, even.cols(), i, ch);
      const Eigen::VectorXd R = autocovariance_from_psd(S, c.fs);
      ch.long_run_variance_factor = R(0) > 0.0 ? c.fs * S(0) / R(0) : 1.0;
      time_window_test(c, rci, R, ch);
      FunctionalVariance fv(S, c.fs, c.nu, c.rho2, N);
      FunctionalVariance fv2(square_process_psd(R, c.fs), c.fs, c.nu, c.rho2, N);
      const Eigen::VectorXd yn = y_nominal.col(i);
      const double spread = std::sqrt((yn.array() - yn.mean()).square().mean());
      if (!(spread > 1e-12 * std::max(1.0, yn.cwiseAbs().maxCoeff()))) {
        out.warnings.push_back(ch.output + ": the nominal output is constant: amplitude, reversal and position tests skipped");
      } else {
        amplitude_test(c, y.col(i), yn, rci, fv, ch, out.warnings);
        reversal_test(c, yn, rci, fv, fv2, ch, out.warnings);
        position_test(c, yn, residual.col(i), fv, ch);
      }
      offset_test(c, residual.col(i), fv, ch);
    }
    const auto fire = [&](bool f, const char* family) {
      if (f) out.fired.push_back(std::string(family) + ":" + ch.output);
    };
    fire(!ch.bands.empty(), "model_error");
    fire(!ch.peaks.empty(), "residual_peak");
    fire(std::any_of(ch.windows.begin(), ch.windows.end(), [](const ResidualWindow& w) { return w.flagged; }), "time_window");
    fire(ch.amplitude.flagged, "amplitude");
    fire(ch.reversal.flagged, "reversal");
    fire(ch.position.flagged, "position");
    fire(ch.offset.flagged, "offset_drift");
    fire(ch.asymmetry.flagged, "asymmetry");
    out.outputs.push_back(std::move(ch));
  }
  out.any_mismatch = !out.fired.empty();
  return out;
}

}  // namespace detail

std::string MismatchLocation::brief_report() const {
  std::ostringstream s;
  s << (any_mismatch ? "mismatch found" : "no significant mismatch") << " (family level " << format_number(family_level, 3)
    << ", nfft " << nfft << ", " << segments << " averages, nu = " << format_number(dof, 3) << ")";
  for (const auto& ch : outputs) {
    s << "\n" << ch.output << ": residual RMS " << format_number(ch.residual_rms);
    for (const auto& b : ch.bands)
      s << "\n  model error " << format_number(b.lo_hz) << ".." << format_number(b.hi_hz) << " Hz, peak " << format_number(b.peak_hz)
        << " Hz |E| = " << format_number(b.peak_gain) << " (input " << b.input_name << ", coherence "
        << format_number(b.peak_coherence, 3) << ")";
    for (const auto& p : ch.peaks)
      s << "\n  residual peak " << format_number(p.freq_hz) << " Hz, amplitude " << format_number(p.amplitude) << ", "
        << format_number(p.prominence_db, 3) << " dB above the floor";
    for (const auto& w : ch.windows)
      if (w.flagged)
        s << "\n  energy " << format_number(w.energy_ratio, 3) << " x floor in " << format_number(w.t0_s) << ".."
          << format_number(w.t1_s) << " s";
    if (ch.amplitude.flagged)
      s << "\n  amplitude-dependent gain: " << format_number(ch.amplitude.gain_low) << " (low) vs "
        << format_number(ch.amplitude.gain_high) << " (high), z = " << format_number(ch.amplitude.z, 3);
    if (ch.reversal.flagged)
      s << "\n  reversal-dependent: energy ratio " << format_number(ch.reversal.energy_ratio, 3) << " (z = "
        << format_number(ch.reversal.energy_z, 3) << "), sign correlation " << format_number(ch.reversal.sign_correlation, 3)
        << " (z = " << format_number(ch.reversal.sign_z, 3) << ")";
    if (ch.position.flagged)
      s << "\n  position-dependent mean: F = " << format_number(ch.position.f_statistic, 3) << ", p = "
        << format_number(ch.position.p_value, 3);
    if (ch.asymmetry.flagged)
      s << "\n  asymmetric (one-sided) dependence on the input: partial coherence with even functions of it "
        << format_number(ch.asymmetry.peak_partial_coherence, 3) << " at " << format_number(ch.asymmetry.peak_hz) << " Hz (threshold "
        << format_number(ch.asymmetry.threshold, 3) << ")";
    if (ch.offset.flagged)
      s << "\n  offset " << format_number(ch.offset.offset) << " +- " << format_number(ch.offset.offset_se) << ", drift "
        << format_number(ch.offset.slope_per_s) << " +- " << format_number(ch.offset.slope_se) << " per s";
  }
  for (const auto& w : warnings) s << "\nwarning: " << w;
  return s.str();
}

}  // namespace sysid
