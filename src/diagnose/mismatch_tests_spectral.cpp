// Tests 1, 2 and 8 of locate_mismatch, the ones read off spectra: the model-error
// FRF's joint coherence, narrow-band residual peaks above a local floor, and the
// partial coherence with even functions of the input (method in
// include/sysid/diagnose/mismatch_location.hpp; shared pieces in
// src/diagnose/detail/mismatch_location_tests.hpp).
#include "diagnose/detail/mismatch_location_tests.hpp"

#include <sysid/core/distributions.hpp>
#include <sysid/core/format_number.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace sysid::detail::mismatch {

namespace {

std::vector<std::pair<Eigen::Index, Eigen::Index>> runs_of(const std::vector<Eigen::Index>& idx, Eigen::Index gap) {
  std::vector<std::pair<Eigen::Index, Eigen::Index>> runs;
  for (const Eigen::Index k : idx) {
    if (!runs.empty() && k - runs.back().second <= gap + 1) runs.back().second = k;
    else runs.emplace_back(k, k);
  }
  return runs;
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

/// f - mean(f) when f varies beyond round-off of its own size, else empty (a
/// constant function: a binary input's square).
Eigen::VectorXd centred_if_varying(const Eigen::VectorXd& f) {
  Eigen::VectorXd centred = f.array() - f.mean();
  if (!(centred.cwiseAbs().maxCoeff() > 1e-9 * f.cwiseAbs().maxCoeff())) return {};
  return centred;
}

}  // namespace

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

}  // namespace sysid::detail::mismatch
