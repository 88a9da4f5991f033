// Tests 3-7 of locate_mismatch, the ones read off the time series: residual energy
// per time window, amplitude-dependent gain, behaviour at velocity reversals,
// position-dependent mean, offset and drift (method in
// include/sysid/diagnose/mismatch_location.hpp; shared pieces in
// src/diagnose/detail/mismatch_location_tests.hpp).
#include "diagnose/detail/mismatch_location_tests.hpp"

#include <sysid/core/distributions.hpp>
#include <sysid/core/median.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

namespace sysid::detail::mismatch {

namespace {

/// q-quantile of a sorted vector with linear interpolation.
double sorted_quantile(const std::vector<double>& s, double q) {
  const double pos = q * static_cast<double>(s.size() - 1);
  const auto i = static_cast<std::size_t>(std::floor(pos));
  if (i + 1 >= s.size()) return s.back();
  const double t = pos - static_cast<double>(i);
  return s[i] + t * (s[i + 1] - s[i]);
}

}  // namespace

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

}  // namespace sysid::detail::mismatch
