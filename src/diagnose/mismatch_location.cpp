// Mismatch location for `sysid diagnose`: the driver of
// include/sysid/diagnose/mismatch_location.hpp (method and references there) and
// its report. The spectral variance estimator and the tests are in
// mismatch_spectral_variance.cpp, mismatch_tests_spectral.cpp and
// mismatch_tests_time.cpp (src/diagnose/detail/mismatch_location_tests.hpp); the
// Beta and F distributions in core/distributions.hpp.
#include <sysid/diagnose/mismatch_location.hpp>

#include <sysid/core/format_number.hpp>
#include <sysid/spectral/frf.hpp>
#include <sysid/spectral/welch.hpp>
#include <sysid/spectral/window.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "diagnose/detail/mismatch_location_tests.hpp"

namespace sysid {

namespace detail {

namespace mismatch {
namespace {

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
}  // namespace mismatch

MismatchLocation locate_mismatch_impl(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y, const Eigen::MatrixXd& residual,
                                      const Eigen::MatrixXd& y_nominal, double Ts, const MismatchLocationOptions& o) {
  using namespace mismatch;
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
