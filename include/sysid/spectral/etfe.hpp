#pragma once
/// @file
/// Purpose: the empirical transfer function estimate (ETFE): the ratio of output
/// and input DFTs over whole records, for periodic excitation (multisines with an
/// integer number of periods), optionally averaged over periods and smoothed in
/// frequency; MIMO from several experiments.
///
/// Method: Ljung, System Identification, 2nd ed., sec. 6.3 (eq. 6.24 ETFE, eq. 6.46
/// smoothed ETFE); Pintelon & Schoukens, System Identification: A Frequency Domain
/// Approach, 2nd ed., sec. 2.4 and 3.x (periodic excitation, averaging over periods).
/// For each experiment e the record (after `transient_periods` whole periods are
/// dropped) is cut into R_e periods of P samples, and the DFTs of the periods are
/// averaged: U_e(k), Y_e(k), k = 0..floor(P/2), f_k = k fs / P. Per bin,
///   S_uu(k) = sum_e U_e U_e^H (m x m),  S_yu(k) = sum_e Y_e U_e^H (l x m),
/// optionally smoothed with Hann weights over 2w + 1 neighbouring bins (Ljung's
/// smoothed ETFE, weights proportional to |U|^2 through S_uu), and
///   H(k) = S_yu(k) S_uu(k)^{-1}.
/// One SISO experiment without smoothing gives H = Y/U; m experiments with
/// independent inputs give H = [Y_1..Y_m] [U_1..U_m]^{-1}. For a noise-free system in
/// periodic steady state driven by a signal of period P, H is exact at every excited
/// bin (no leakage: the record holds whole periods).
/// A bin is "excited" when the smallest eigenvalue of S_uu exceeds
/// excitation_threshold times the largest eigenvalue of S_uu over all bins; H is NaN
/// at bins that are not excited (for a multisine: every bin it leaves out).
///
/// Preconditions (std::invalid_argument): data valid (IoData::validate);
/// period == 0 (the whole record is one period; then all experiments must have the
/// same length) or period >= 2; transient_periods >= 0; at least one whole period per
/// experiment after the transient; smoothing_bins >= 0; 0 <= excitation_threshold < 1.
/// Numerical aspects: O(experiments R (m + l) P log P) for the DFTs (kissfft, any P; fastest for
/// small prime factors), O(P (2w + 1) (m^2 + l m) + P m^3) for the solves.
/// Without smoothing and with fewer than m experiments S_uu is singular: no bin is excited.
#include <sysid/core/io_data.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/FFT>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

struct EtfeOptions {
  Eigen::Index period = 0;             ///< samples per excitation period P; 0: the whole record is one period
  Eigen::Index transient_periods = 0;  ///< whole periods dropped at the start of each experiment (settling)
  Eigen::Index smoothing_bins = 0;     ///< half-width w of the Hann frequency window (2w + 1 bins); 0 = raw ETFE
  double excitation_threshold = 1e-10;  ///< excited: lambda_min(S_uu(k)) > threshold * max_k lambda_max(S_uu(k))
};

struct EtfeResult {
  Eigen::VectorXd freq_hz;          ///< floor(P/2) + 1 frequencies k fs / P
  std::vector<Eigen::MatrixXcd> H;  ///< l x m per frequency; NaN where not excited
  std::vector<bool> excited;        ///< per frequency
  Eigen::VectorXd input_condition;  ///< per frequency: condition number of S_uu (infinite if singular)
  Eigen::Index periods = 0;         ///< periods averaged, summed over experiments
  std::vector<std::string> warnings;
};

/// Purpose, method, preconditions: see the file comment.
inline EtfeResult etfe(const IoData& data, const EtfeOptions& options = {}) {
  const std::string who = "etfe";
  data.validate();
  if (options.period != 0 && options.period < 2) throw std::invalid_argument(who + ": need period == 0 or period >= 2");
  if (options.transient_periods < 0) throw std::invalid_argument(who + ": need transient_periods >= 0");
  if (options.smoothing_bins < 0) throw std::invalid_argument(who + ": need smoothing_bins >= 0");
  if (!(options.excitation_threshold >= 0.0 && options.excitation_threshold < 1.0))
    throw std::invalid_argument(who + ": need 0 <= excitation_threshold < 1");
  const Eigen::Index m = data.inputs(), l = data.outputs();
  if (m < 1 || l < 1) throw std::invalid_argument(who + ": need inputs >= 1 and outputs >= 1");
  Eigen::Index P = options.period;
  if (P == 0) {
    P = data.experiments.front().samples();
    for (const auto& e : data.experiments)
      if (e.samples() != P)
        throw std::invalid_argument(who + ": with period == 0 need experiments of equal length (" + std::to_string(P) +
                                    " vs " + std::to_string(e.samples()) + ")");
    if (options.transient_periods != 0) throw std::invalid_argument(who + ": with period == 0 need transient_periods == 0");
  }
  if (P < 2) throw std::invalid_argument(who + ": need at least 2 samples per period");
  const Eigen::Index bins = P / 2 + 1;
  const auto nb = static_cast<std::size_t>(bins);
  using Complex = std::complex<double>;

  EtfeResult r;
  r.freq_hz.resize(bins);
  for (Eigen::Index k = 0; k < bins; ++k) r.freq_hz(k) = static_cast<double>(k) / (data.Ts * static_cast<double>(P));
  std::vector<Eigen::MatrixXcd> Suu(nb, Eigen::MatrixXcd::Zero(m, m)), Syu(nb, Eigen::MatrixXcd::Zero(l, m));
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  Eigen::MatrixXcd U(bins, m), Y(bins, l);
  Eigen::VectorXcd spectrum(bins);
  std::vector<double> segment(static_cast<std::size_t>(P));
  for (std::size_t e = 0; e < data.experiments.size(); ++e) {
    const Experiment& ex = data.experiments[e];
    const Eigen::Index R = ex.samples() / P - options.transient_periods;
    if (R < 1)
      throw std::invalid_argument(who + ": need samples >= (transient_periods + 1) * period in experiment " +
                                  std::to_string(e + 1) + " (have " + std::to_string(ex.samples()) + ")");
    r.periods += R;
    const Eigen::Index first = options.transient_periods * P;
    // Averaging the period DFTs equals the DFT of the averaged period (linearity): one FFT per channel.
    auto average_dft = [&](const Eigen::MatrixXd& x, Eigen::MatrixXcd& X) {
      for (Eigen::Index c = 0; c < x.cols(); ++c) {
        for (Eigen::Index n = 0; n < P; ++n) {
          double s = 0.0;
          for (Eigen::Index q = 0; q < R; ++q) s += x(first + q * P + n, c);
          segment[static_cast<std::size_t>(n)] = s / static_cast<double>(R);
        }
        fft.fwd(spectrum.data(), segment.data(), P);
        X.col(c) = spectrum;
      }
    };
    average_dft(ex.u, U);
    average_dft(ex.y, Y);
    for (std::size_t k = 0; k < nb; ++k) {
      const auto kk = static_cast<Eigen::Index>(k);
      Suu[k].noalias() += U.row(kk).transpose() * U.row(kk).conjugate();  // U_e U_e^H
      Syu[k].noalias() += Y.row(kk).transpose() * U.row(kk).conjugate();  // Y_e U_e^H
    }
  }
  if (options.smoothing_bins > 0) {
    const Eigen::Index w = options.smoothing_bins;
    std::vector<Eigen::MatrixXcd> su(nb, Eigen::MatrixXcd::Zero(m, m)), sy(nb, Eigen::MatrixXcd::Zero(l, m));
    for (Eigen::Index k = 0; k < bins; ++k)
      for (Eigen::Index d = -w; d <= w; ++d) {
        const Eigen::Index j = k + d;
        if (j < 0 || j >= bins) continue;
        const double weight = 0.5 * (1.0 + std::cos(std::numbers::pi * static_cast<double>(d) / static_cast<double>(w + 1)));
        su[static_cast<std::size_t>(k)] += weight * Suu[static_cast<std::size_t>(j)];
        sy[static_cast<std::size_t>(k)] += weight * Syu[static_cast<std::size_t>(j)];
      }
    Suu.swap(su);
    Syu.swap(sy);
  }
  std::vector<Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>> eig(nb);
  double peak = 0.0;
  for (std::size_t k = 0; k < nb; ++k) {
    eig[k].compute(Suu[k]);
    peak = std::max(peak, eig[k].eigenvalues()(m - 1));
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r.H.resize(nb);
  r.excited.assign(nb, false);
  r.input_condition.resize(bins);
  Eigen::Index n_excited = 0;
  for (std::size_t k = 0; k < nb; ++k) {
    const Eigen::VectorXd lam = eig[k].eigenvalues();
    const bool ok = peak > 0.0 && lam(0) > options.excitation_threshold * peak && lam(0) > 0.0;
    r.input_condition(static_cast<Eigen::Index>(k)) = lam(0) > 0.0 ? lam(m - 1) / lam(0) : std::numeric_limits<double>::infinity();
    r.excited[k] = ok;
    if (ok) {
      ++n_excited;
      r.H[k] = Syu[k] * (eig[k].eigenvectors() * lam.cwiseInverse().asDiagonal() * eig[k].eigenvectors().adjoint());
    } else {
      r.H[k] = Eigen::MatrixXcd::Constant(l, m, Complex(nan, nan));
    }
  }
  if (n_excited == 0) {
    std::ostringstream s;
    s << "no excited frequency: the inputs carry no power" << (static_cast<Eigen::Index>(data.experiments.size()) < m && options.smoothing_bins == 0
                                                                  ? " in enough independent directions (need >= m experiments or smoothing)"
                                                                  : "");
    r.warnings.push_back(s.str());
  }
  return r;
}

/// Convenience overload for one record: u (N x m), y (N x l), sampling frequency fs.
template <class DerivedU, class DerivedY>
EtfeResult etfe(const Eigen::MatrixBase<DerivedU>& u, const Eigen::MatrixBase<DerivedY>& y, double fs_hz,
                const EtfeOptions& options = {}) {
  if (!(fs_hz > 0.0) || !std::isfinite(fs_hz)) throw std::invalid_argument("etfe: need 0 < fs < infinity");
  return etfe(IoData(Eigen::MatrixXd(u), Eigen::MatrixXd(y), 1.0 / fs_hz), options);
}

}  // namespace sysid
