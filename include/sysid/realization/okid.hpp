#pragma once
/// @file
/// Purpose: OKID, observer/Kalman filter identification: the Markov parameters
/// of a (lightly damped) system from arbitrary input/output records, for ERA
/// (realization/era.hpp). Robust where a direct FIR fit fails: a lightly
/// damped system's impulse response is far longer than any affordable FIR, but
/// that of an observer with poles placed inside the unit circle is short.
///
/// Method (Juang, Phan, Horta & Longman 1993): with an observer gain G the
/// system x(k+1) = A x + B u, y = C x + D u is rewritten as
///   x(k+1) = Abar x(k) + Bbar v(k),  Abar = A + G C,  Bbar = [B + G D, -G],
///   v(k) = [u(k); y(k)],
/// so that, if Abar^p ~ 0 (deadbeat or Kalman observer, eq. 10-14),
///   y(k) = D u(k) + sum_{i=1}^{p} Ybar_i v(k - i) + eps(k),
///   Ybar_i = C Abar^(i-1) Bbar = [Ybar_i^(1), -Ybar_i^(2)]      (observer Markov parameters).
/// 1. Least squares for [D, Ybar_1, ..., Ybar_p] over the samples k >= p of
///    every record (each record its own start, so no initial condition is
///    assumed and records never see each other's samples); rows streamed through
///    a Householder QR (core/streaming_qr.hpp), never normal equations; a
///    rank-deficient R is solved by complete orthogonal decomposition.
/// 2. System Markov parameters (eq. 23-24 of the paper, written with M2_i =
///    -Ybar_i^(2), the fitted coefficient of y(k - i)):
///      Y_0 = D,  Y_k = Ybar_k^(1) + sum_{i=1}^{min(k,p)} M2_i Y_(k-i)   (Ybar_k^(1) = 0 for k > p).
/// 3. Observer-gain Markov parameters C A^(k-1) G (eq. 28):
///      Y^o_1 = -M2_1,  Y^o_k = -M2_k + sum_{i=1}^{k-1} M2_i Y^o_(k-i)   (M2_k = 0 for k > p).
///    Returned with the Kalman-predictor sign, C A^(k-1) K with K = -G
///    (x^(k+1) = A x^ + B u + K (y - C x^ - D u)).
/// With noisy data the least-squares observer is an estimate of the steady-state
/// Kalman filter (paper, sec. 4): p must be large enough that the Kalman
/// filter's impulse response has decayed within p samples.
/// For ERA on the result: beyond h[p] the Markov parameters follow the order-p l
/// recursion of step 2, so their Hankel matrix has a genuine rank gap at p l as
/// well; give ERA's automatic order rule a max_order below p l.
///
/// Preconditions (std::invalid_argument): p = observer_order >= 1;
/// markov_count >= 0; data with m >= 1 inputs; more equations than unknowns
/// (sum over records of N_e - p > m + p (m + l)). The data are deviations from an
/// operating point (remove means beforehand, e.g. remove_means() in io_data.hpp).
/// Numerical aspects: O(N q^2) flops with q = m + p (m + l) unknowns per output,
/// memory O(q^2) whatever N; the recovery is O(count p l^2 m).
///
/// References: J.-N. Juang, M. Phan, L. G. Horta, R. W. Longman, "Identification
/// of observer/Kalman filter Markov parameters: theory and experiments", Journal
/// of Guidance, Control, and Dynamics 16(2):320-329, 1993.
#include <sysid/core/io_data.hpp>
#include <sysid/core/streaming_qr.hpp>
#include <sysid/realization/markov_parameters.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

struct OkidOptions {
  /// p: number of observer Markov parameters. Needs p l >= n for a deadbeat
  /// observer to exist; with noise, larger (the Kalman filter's decay time in samples).
  int observer_order = 20;
  /// Number of system Markov parameters h[1..count] returned (plus h[0] = D);
  /// 0 = 4 p. Beyond p they follow from the identified observer (step 2).
  int markov_count = 0;
  bool estimate_feedthrough = true;  ///< false: D = 0 and u(k) is left out of the regression
};

struct OkidResult {
  MarkovParameters markov;                   ///< h[0] = D, h[k] = C A^(k-1) B, k = 1..markov_count
  std::vector<Eigen::MatrixXd> gain_markov;  ///< C A^(k-1) K, k = 1..markov_count (l x l), K = Kalman predictor gain
  std::vector<Eigen::MatrixXd> observer_markov;  ///< Ybar_i = [C Abar^(i-1) Bbar], i = 1..p (l x (m + l))
  double condition = 0.0;     ///< of the column-scaled regressor (from R)
  double residual_rms = 0.0;  ///< RMS one-step prediction error of the observer model
  Eigen::Index equations = 0;
  bool rank_deficient = false;
  std::vector<std::string> warnings;
};

/// Purpose: OKID on one or several records (file comment).
/// Warnings: rank-deficient or ill-conditioned regression (cond > 1e10: input
/// not persistently exciting); observer Markov parameters not decayed
/// (||Ybar_p|| > 10 % of max ||Ybar_i||: increase p); fewer than 5 equations per
/// unknown.
inline OkidResult okid(const IoData& data, const OkidOptions& options = {}) {
  data.validate();
  const Eigen::Index m = data.inputs(), l = data.outputs();
  const int p = options.observer_order;
  if (p < 1) throw std::invalid_argument("okid: need observer_order p >= 1");
  if (options.markov_count < 0) throw std::invalid_argument("okid: need markov_count >= 0");
  if (m < 1) throw std::invalid_argument("okid: need at least one input");
  const int count = options.markov_count > 0 ? options.markov_count : 4 * p;
  const Eigen::Index d0 = options.estimate_feedthrough ? m : 0;  // columns of u(k)
  const Eigen::Index q = d0 + static_cast<Eigen::Index>(p) * (m + l);
  Eigen::Index rows_total = 0;
  for (const Experiment& e : data.experiments) rows_total += std::max<Eigen::Index>(0, e.samples() - p);
  if (rows_total <= q)
    throw std::invalid_argument("okid: need more equations than unknowns (" + std::to_string(rows_total) + " <= " +
                                std::to_string(q) + "): use more samples or a smaller observer_order");

  StreamingQR qr(q + l);
  for (const Experiment& e : data.experiments) {
    const Eigen::Index N = e.samples();
    Eigen::Index k = p;
    while (k < N) {
      const Eigen::Index take = std::min(qr.free_rows(), N - k);
      auto rows = qr.next_rows(take);
      for (Eigen::Index r = 0; r < take; ++r) {
        const Eigen::Index t = k + r;
        if (d0 > 0) rows.row(r).head(m) = e.u.row(t);
        for (Eigen::Index i = 1; i <= p; ++i) {
          const Eigen::Index c = d0 + (i - 1) * (m + l);
          rows.row(r).segment(c, m) = e.u.row(t - i);
          rows.row(r).segment(c + m, l) = e.y.row(t - i);
        }
        rows.row(r).tail(l) = e.y.row(t);
      }
      qr.commit_rows(take);
      k += take;
    }
  }
  const Eigen::MatrixXd R = qr.r();
  const Eigen::MatrixXd R11 = R.topLeftCorner(q, q);

  OkidResult res;
  res.equations = rows_total;
  const Eigen::VectorXd col_norm = R11.colwise().norm().transpose();
  Eigen::MatrixXd scaled = R11;
  for (Eigen::Index c = 0; c < q; ++c)
    if (col_norm[c] > 0.0) scaled.col(c) /= col_norm[c];
  const Eigen::VectorXd sv = Eigen::BDCSVD<Eigen::MatrixXd>(scaled).singularValues();
  res.condition = sv[q - 1] > 0.0 ? sv[0] / sv[q - 1] : std::numeric_limits<double>::infinity();
  // Solve in the scaled variables (so the rank decision ignores units), then unscale.
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
  cod.setThreshold(static_cast<double>(q) * std::numeric_limits<double>::epsilon() * 10.0);
  cod.compute(scaled);
  res.rank_deficient = cod.rank() < q;
  Eigen::MatrixXd theta = cod.solve(R.topRightCorner(q, l));  // q x l
  for (Eigen::Index c = 0; c < q; ++c) theta.row(c) = col_norm[c] > 0.0 ? Eigen::RowVectorXd(theta.row(c) / col_norm[c])
                                                                         : Eigen::RowVectorXd::Zero(l);
  const double rss = (R11 * theta - R.topRightCorner(q, l)).squaredNorm() + R.bottomRightCorner(l, l).squaredNorm();
  res.residual_rms = std::sqrt(rss / static_cast<double>(rows_total * l));

  // Unpack: D (l x m), M1_i (l x m), M2_i (l x l).
  const Eigen::MatrixXd D = d0 > 0 ? Eigen::MatrixXd(theta.topRows(m).transpose()) : Eigen::MatrixXd::Zero(l, m);
  std::vector<Eigen::MatrixXd> M1(static_cast<std::size_t>(p)), M2(static_cast<std::size_t>(p));
  res.observer_markov.resize(static_cast<std::size_t>(p));
  double ybar_max = 0.0;
  for (int i = 1; i <= p; ++i) {
    const Eigen::Index c = d0 + (i - 1) * (m + l);
    const std::size_t si = static_cast<std::size_t>(i - 1);
    M1[si] = theta.middleRows(c, m).transpose();
    M2[si] = theta.middleRows(c + m, l).transpose();
    res.observer_markov[si] = theta.middleRows(c, m + l).transpose();  // [Ybar^(1), -Ybar^(2)]
    ybar_max = std::max(ybar_max, res.observer_markov[si].norm());
  }

  MarkovParameters& mp = res.markov;
  mp.Ts = data.Ts;
  mp.input_names = data.input_names;
  mp.output_names = data.output_names;
  mp.h.reserve(static_cast<std::size_t>(count) + 1);
  mp.h.push_back(D);
  for (int k = 1; k <= count; ++k) {
    Eigen::MatrixXd Yk = k <= p ? M1[static_cast<std::size_t>(k - 1)] : Eigen::MatrixXd::Zero(l, m);
    for (int i = 1; i <= std::min(k, p); ++i) Yk.noalias() += M2[static_cast<std::size_t>(i - 1)] * mp.h[static_cast<std::size_t>(k - i)];
    mp.h.push_back(std::move(Yk));
  }
  // C A^(k-1) G recursion, then the Kalman sign K = -G.
  std::vector<Eigen::MatrixXd> cag;
  cag.reserve(static_cast<std::size_t>(count));
  for (int k = 1; k <= count; ++k) {
    Eigen::MatrixXd Yo = k <= p ? Eigen::MatrixXd(-M2[static_cast<std::size_t>(k - 1)]) : Eigen::MatrixXd::Zero(l, l);
    for (int i = 1; i <= std::min(k - 1, p); ++i) Yo.noalias() += M2[static_cast<std::size_t>(i - 1)] * cag[static_cast<std::size_t>(k - i - 1)];
    cag.push_back(std::move(Yo));
  }
  res.gain_markov.reserve(cag.size());
  for (const Eigen::MatrixXd& g : cag) res.gain_markov.push_back(-g);

  if (res.rank_deficient)
    res.warnings.push_back("rank-deficient regression (rank " + std::to_string(cod.rank()) + " of " + std::to_string(q) +
                           "): noise-free data with p l above the system order, or an input that is not persistently exciting of "
                           "order " + std::to_string(p) + "; a minimum-norm solution was used");
  else if (res.condition > 1e10)
    res.warnings.push_back("ill-conditioned regression (cond = " + std::to_string(res.condition) +
                           "): the input barely excites some directions");
  if (p >= 4 && ybar_max > 0.0 && res.observer_markov.back().norm() > 0.1 * ybar_max)
    res.warnings.push_back("observer Markov parameters have not decayed within p = " + std::to_string(p) +
                           " (last/peak = " + std::to_string(res.observer_markov.back().norm() / ybar_max) +
                           "): increase observer_order");
  if (rows_total < 5 * q)
    res.warnings.push_back("only " + std::to_string(rows_total) + " equations for " + std::to_string(q) +
                           " unknowns per output (< 5 per unknown): the estimates are noisy");
  return res;
}

}  // namespace sysid
