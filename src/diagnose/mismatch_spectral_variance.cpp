// The spectral variance estimator of locate_mismatch: the variance of linear
// functionals sum_t x_t r_t of a stationary residual from its Welch spectrum, and
// the spectra it needs (src/diagnose/detail/mismatch_location_tests.hpp; method in
// include/sysid/diagnose/mismatch_location.hpp).
#include "diagnose/detail/mismatch_location_tests.hpp"

#include <sysid/spectral/window.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

namespace sysid::detail::mismatch {

namespace {

Eigen::Index next_pow2(Eigen::Index n) {
  Eigen::Index p = 1;
  while (p < n) p *= 2;
  return p;
}

}  // namespace

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

FunctionalVariance::FunctionalVariance(const Eigen::VectorXd& S, double fs, double nu, const std::vector<double>& rho2, Eigen::Index N)
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

Eigen::VectorXcd FunctionalVariance::transform(const Eigen::VectorXd& x) {
  std::fill(m_buffer.begin(), m_buffer.end(), 0.0);
  std::copy(x.data(), x.data() + x.size(), m_buffer.begin());
  Eigen::VectorXcd X(m_M / 2 + 1);
  m_fft.fwd(X.data(), m_buffer.data(), m_M);
  return X;
}

double FunctionalVariance::covariance(const Eigen::VectorXcd& X, const Eigen::VectorXcd& Y) const {
  double s = 0.0;
  const Eigen::Index half = m_M / 2;
  for (Eigen::Index m = 0; m <= half; ++m) {
    const double mult = (m == 0 || m == half) ? 1.0 : 2.0;
    s += mult * m_G(m) * std::real(std::conj(X(m)) * Y(m));
  }
  return s / static_cast<double>(m_M);
}

Moment FunctionalVariance::variance(const Eigen::VectorXcd& X) const {
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

}  // namespace sysid::detail::mismatch
