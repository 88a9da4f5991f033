// Closed-loop detector (see include/sysid/diagnose/feedback_check.hpp).
#include "sysid/diagnose/feedback_check.hpp"

#include <sysid/core/distributions.hpp>
#include <sysid/core/format_number.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sysid {

namespace {

using Qr = Eigen::ColPivHouseholderQR<Eigen::MatrixXd>;

/// x minus its least-squares projection on the first `rank` columns of qr's Q.
template <typename Factorisation>
Eigen::MatrixXd project_out(const Factorisation& qr, Eigen::Index rank, Eigen::MatrixXd x) {
  if (rank == 0) return x;
  x = qr.householderQ().adjoint() * x;
  x.topRows(rank).setZero();
  return qr.householderQ() * x;
}

/// RMS about the mean; 0 for a constant column (spread below 1e-12 of its size).
double spread(const Eigen::Ref<const Eigen::VectorXd>& x) {
  const double s = std::sqrt((x.array() - x.mean()).square().mean());
  return s > 1e-12 * x.cwiseAbs().maxCoeff() ? s : 0.0;
}

/// Upper quantile of chi-square(dof); exact for dof = 1 (the Wilson-Hilferty form
/// of chi_square_quantile is for dof >= 2).
double chi_square_upper(double p, int dof) {
  if (dof == 1) {
    const double z = normal_quantile(1.0 - p / 2.0);
    return z * z;
  }
  return chi_square_quantile(1.0 - p, static_cast<double>(dof));
}

std::string channel(const char* what, Eigen::Index k) { return std::string(what) + " " + std::to_string(k + 1); }

}  // namespace

OutputFeedbackCheck check_output_feedback(const Eigen::Ref<const Eigen::MatrixXd>& u,
                                          const Eigen::Ref<const Eigen::MatrixXd>& y,
                                          const Eigen::Ref<const Eigen::MatrixXd>& y_simulated, double Ts,
                                          const OutputFeedbackOptions& o) {
  const Eigen::Index N = u.rows(), m = u.cols(), l = y.cols();
  const auto bad = [](const std::string& what) { return std::invalid_argument("check_output_feedback: need " + what); };
  if (m < 1 || l < 1) throw bad("at least one input and one output");
  if (y.rows() != N || y_simulated.rows() != N)
    throw bad("u, y and y_simulated with the same rows (" + std::to_string(N) + ", " + std::to_string(y.rows()) + ", " +
              std::to_string(y_simulated.rows()) + ")");
  if (y_simulated.cols() != l)
    throw bad("y_simulated.cols() == y.cols() (" + std::to_string(y_simulated.cols()) + " != " + std::to_string(l) + ")");
  if (!(Ts > 0.0) || !std::isfinite(Ts)) throw bad("0 < Ts < inf");
  if (o.lags < 1 || o.output_lags < 0 || o.input_delay < 0 || o.input_lags < o.input_delay)
    throw bad("lags >= 1, output_lags >= 0 and 0 <= input_delay <= input_lags");
  if (!(o.significance > 0.0 && o.significance < 1.0)) throw bad("0 < significance < 1");
  if (!(o.predictable_tolerance > 0.0 && o.predictable_tolerance < 1.0)) throw bad("0 < predictable_tolerance < 1");
  const Eigen::Index K = o.lags, t0 = std::max(o.output_lags, o.input_lags);
  const Eigen::Index parameters = 1 + l * (2 * o.output_lags + 1) + m * (o.input_lags - o.input_delay + 1) + K;
  if (N < t0 + K + 4 * parameters)
    throw bad("at least max(output_lags, input_lags) + lags + 4 parameters = " + std::to_string(t0 + K + 4 * parameters) +
              " samples (have " + std::to_string(N) + ")");
  if (!u.allFinite() || !y.allFinite() || !y_simulated.allFinite()) throw bad("finite u, y and y_simulated");

  const Eigen::MatrixXd v = y - y_simulated;
  const Eigen::Index n = N - K - t0;  // regression rows t = t0 .. N - 1 - K
  std::vector<double> u_scale(static_cast<std::size_t>(m)), v_scale(static_cast<std::size_t>(l));
  Eigen::Index live_u = 0, live_v = 0;
  for (Eigen::Index j = 0; j < m; ++j) live_u += (u_scale[static_cast<std::size_t>(j)] = spread(u.col(j))) > 0.0;
  for (Eigen::Index i = 0; i < l; ++i) live_v += (v_scale[static_cast<std::size_t>(i)] = spread(v.col(i))) > 0.0;
  // Column of x (scaled to unit RMS about its mean) shifted by `shift` samples.
  const auto column = [&](const Eigen::Ref<const Eigen::VectorXd>& x, double scale, Eigen::Index shift) {
    return Eigen::VectorXd((x.segment(t0 + shift, n).array() - x.mean()) / scale);
  };

  // The past block: constant, lagged residuals of every output, lagged inputs,
  // the simulation and its lags (functions of past inputs: what the nominal's
  // poles contribute to the mismatch, which lagged inputs alone absorb slowly).
  std::vector<double> s_scale(static_cast<std::size_t>(l));
  Eigen::Index live_s = 0;
  for (Eigen::Index i = 0; i < l; ++i) live_s += (s_scale[static_cast<std::size_t>(i)] = spread(y_simulated.col(i))) > 0.0;
  const Eigen::Index sim_lags = o.output_lags + 1;  // y_simulated(t) .. y_simulated(t - output_lags)
  Eigen::MatrixXd past(n, 1 + live_v * o.output_lags + live_u * (o.input_lags - o.input_delay + 1) + live_s * sim_lags);
  Eigen::Index c = 0;
  past.col(c++).setOnes();
  for (Eigen::Index i = 0; i < l; ++i)
    if (v_scale[static_cast<std::size_t>(i)] > 0.0)
      for (Eigen::Index k = 1; k <= o.output_lags; ++k) past.col(c++) = column(v.col(i), v_scale[static_cast<std::size_t>(i)], -k);
  for (Eigen::Index j = 0; j < m; ++j)
    if (u_scale[static_cast<std::size_t>(j)] > 0.0)
      for (Eigen::Index k = o.input_delay; k <= o.input_lags; ++k)
        past.col(c++) = column(u.col(j), u_scale[static_cast<std::size_t>(j)], -k);
  for (Eigen::Index i = 0; i < l; ++i)
    if (s_scale[static_cast<std::size_t>(i)] > 0.0)
      for (Eigen::Index k = 0; k < sim_lags; ++k) past.col(c++) = column(y_simulated.col(i), s_scale[static_cast<std::size_t>(i)], -k);
  const Eigen::HouseholderQR<Eigen::MatrixXd> past_qr(past);
  const Eigen::Index past_rank = past.cols();

  // Each input's future block with the past projected out, and its rank: columns
  // below predictable_tolerance of their RMS (sqrt n) do not count.
  const double floor = o.predictable_tolerance * std::sqrt(static_cast<double>(n));
  std::vector<Eigen::MatrixXd> future(static_cast<std::size_t>(m));
  std::vector<Qr> future_qr(static_cast<std::size_t>(m));
  std::vector<int> dof(static_cast<std::size_t>(m), 0);
  for (Eigen::Index j = 0; j < m; ++j) {
    const auto js = static_cast<std::size_t>(j);
    if (u_scale[js] == 0.0) continue;
    Eigen::MatrixXd f(n, K);
    for (Eigen::Index k = 1; k <= K; ++k) f.col(k - 1) = column(u.col(j), u_scale[js], k);
    future[js] = project_out(past_qr, past_rank, std::move(f));
    future_qr[js].compute(future[js]);
    if (future_qr[js].maxPivot() > floor) {
      future_qr[js].setThreshold(floor / future_qr[js].maxPivot());
      dof[js] = static_cast<int>(future_qr[js].rank());
    }
  }
  // Each output's innovation: its residual with the past projected out.
  std::vector<Eigen::VectorXd> innovation(static_cast<std::size_t>(l));
  for (Eigen::Index i = 0; i < l; ++i) {
    const auto is = static_cast<std::size_t>(i);
    if (v_scale[is] == 0.0) continue;
    innovation[is] = project_out(past_qr, past_rank, column(v.col(i), v_scale[is], 0));
    if (innovation[is].squaredNorm() <= 1e-20 * static_cast<double>(n)) innovation[is].resize(0);  // v explained by its past
  }

  OutputFeedbackCheck r;
  r.lags = static_cast<int>(K);
  r.samples = n;
  for (Eigen::Index i = 0; i < l; ++i)
    for (Eigen::Index j = 0; j < m; ++j)
      r.pairs_tested += dof[static_cast<std::size_t>(j)] > 0 && innovation[static_cast<std::size_t>(i)].size() > 0;
  const double level = o.significance / std::max(1, r.pairs_tested);
  double best_ratio = -1.0;
  int best_dof = 0;
  for (Eigen::Index i = 0; i < l; ++i) {
    const Eigen::VectorXd& e = innovation[static_cast<std::size_t>(i)];
    for (Eigen::Index j = 0; j < m; ++j) {
      const auto js = static_cast<std::size_t>(j);
      OutputFeedbackPair p;
      p.input = j;
      p.output = i;
      p.dof = dof[js];
      p.tested = p.dof > 0 && e.size() > 0;
      if (p.tested) {
        const double ssr = e.squaredNorm();
        const Eigen::VectorXd z = future_qr[js].householderQ().adjoint() * e;
        const double explained = z.head(p.dof).squaredNorm();
        const double remaining = std::max(ssr - explained, 1e-300);
        p.explained_share = explained / ssr;
        p.statistic = static_cast<double>(n - past_rank - p.dof) * explained / remaining;
        p.threshold = chi_square_upper(level, p.dof);
        p.p_value = chi_square_sf(p.statistic, static_cast<double>(p.dof));
        p.detected = p.statistic > p.threshold;
        double strongest = -1.0;
        for (Eigen::Index k = 0; k < K; ++k) {
          const double norm2 = future[js].col(k).squaredNorm();
          if (norm2 <= floor * floor) continue;
          const double share = std::pow(future[js].col(k).dot(e), 2) / norm2;
          if (share > strongest) {
            strongest = share;
            p.strongest_lag = static_cast<int>(k + 1);
          }
        }
        const double ratio = p.statistic / p.threshold;
        if (ratio > best_ratio) {
          best_ratio = ratio;
          r.statistic = p.statistic;
          r.threshold = p.threshold;
          r.input = j;
          r.output = i;
          r.strongest_lag_s = static_cast<double>(p.strongest_lag) * Ts;
          best_dof = p.dof;
        }
        r.feedback_detected = r.feedback_detected || p.detected;
        r.tested = true;
      }
      r.pairs.push_back(p);
    }
  }

  const std::string pair = channel("input", r.input) + " and " + channel("output", r.output);
  const std::string numbers = "chi-square " + format_number(r.statistic, 3) + (r.feedback_detected ? " > " : " <= ") +
                              format_number(r.threshold, 3) + " (" + std::to_string(best_dof) + " degrees of freedom) at " +
                              format_number(100.0 * o.significance, 2) + " % over " + std::to_string(r.pairs_tested) +
                              " input-output pair(s), " + std::to_string(K) + " lags";
  if (!r.tested)
    r.evidence = live_u == 0 ? "no feedback test: every input is constant"
                 : live_v == 0 ? "no feedback test: the outputs equal their simulation (no noise to feed back)"
                               : "no feedback test: each input's future is a linear function of its past (a periodic "
                                 "input, which noise fed back would have made unpredictable), or the residuals are functions of their own past";
  else if (r.feedback_detected)
    r.evidence = "the record looks closed-loop: " + channel("input", r.input) + " reacts to the noise of " +
                 channel("output", r.output) + " (its next " + std::to_string(K) +
                 " samples explain part of the simulation residual's innovation, " + numbers + ", strongest " +
                 format_number(1e3 * r.strongest_lag_s, 3) +
                 " ms later): the open-loop simulation from the logged input stays valid, a refit of the nominal's "
                 "dynamics from this record is biased";
  else
    r.evidence = "no sign of feedback: no input's next " + std::to_string(K) +
                 " samples explain the outputs' simulation residual (largest, " + pair + ": " + numbers + ")";
  return r;
}

}  // namespace sysid
