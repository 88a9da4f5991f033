// Implementation of realization/okid.hpp (method and references in the header).
// Compiled once into libsysid: the streaming QR, SVD and complete orthogonal
// decomposition are heavy to instantiate.
#include <sysid/core/format_number.hpp>
#include <sysid/core/identification_warnings.hpp>
#include <sysid/core/streaming_qr.hpp>
#include <sysid/realization/okid.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

OkidResult okid(const IoData& data, const OkidOptions& options) {
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

  require_varying_inputs(data, "okid");
  OkidResult res;
  // The regression has p past inputs per input: they must be linearly independent.
  res.warnings = identification_data_warnings(data, p, "OKID with observer order " + std::to_string(p), "");
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
    res.warnings.push_back("ill-conditioned regression (cond = " + format_number(res.condition) +
                           "): the input barely excites some directions");
  if (p >= 4 && ybar_max > 0.0 && res.observer_markov.back().norm() > 0.1 * ybar_max)
    res.warnings.push_back("observer Markov parameters have not decayed within p = " + std::to_string(p) +
                           " (last/peak = " + format_number(res.observer_markov.back().norm() / ybar_max) +
                           "): increase observer_order");
  if (rows_total < 5 * q)
    res.warnings.push_back("only " + std::to_string(rows_total) + " equations for " + std::to_string(q) +
                           " unknowns per output (< 5 per unknown): the estimates are noisy");
  return res;
}

}  // namespace sysid
