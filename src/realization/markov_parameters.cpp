// Implementation of realization/markov_parameters.hpp (the deconvolution method is
// described in the header).
#include <sysid/core/errors.hpp>
#include <sysid/core/format_number.hpp>
#include <sysid/core/streaming_qr.hpp>
#include <sysid/realization/markov_parameters.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

void MarkovParameters::validate() const {
  if (h.empty()) throw std::invalid_argument("markov-parameters: need at least h[0]");
  const Eigen::Index l = outputs(), m = inputs();
  if (l < 1 || m < 1) throw std::invalid_argument("markov-parameters: need l >= 1 outputs and m >= 1 inputs");
  for (std::size_t k = 0; k < h.size(); ++k) {
    if (h[k].rows() != l || h[k].cols() != m)
      throw std::invalid_argument("markov-parameters: h[" + std::to_string(k) + "] must be " + std::to_string(l) + "x" +
                                  std::to_string(m));
    if (!h[k].allFinite()) throw std::invalid_argument("markov-parameters: h[" + std::to_string(k) + "] has NaN or Inf");
  }
  if (!(Ts > 0.0) || !std::isfinite(Ts)) throw std::invalid_argument("markov-parameters: need Ts > 0");
  if (!input_names.empty() && static_cast<Eigen::Index>(input_names.size()) != m)
    throw std::invalid_argument("markov-parameters: input name count differs from input count");
  if (!output_names.empty() && static_cast<Eigen::Index>(output_names.size()) != l)
    throw std::invalid_argument("markov-parameters: output name count differs from output count");
}

MarkovParameters markov_from_fir(const std::vector<Eigen::MatrixXd>& fir, double Ts,
                                 std::vector<std::string> input_names,
                                 std::vector<std::string> output_names) {
  MarkovParameters mp{fir, Ts, std::move(input_names), std::move(output_names)};
  mp.validate();
  return mp;
}

MarkovParameters markov_parameters(const StateSpace& sys, int count) {
  sys.validate();
  if (!sys.is_discrete()) throw std::invalid_argument("markov_parameters: need a discrete model (Ts > 0)");
  if (count < 0) throw std::invalid_argument("markov_parameters: need count >= 0");
  MarkovParameters mp;
  mp.Ts = sys.Ts;
  mp.input_names = sys.input_names;
  mp.output_names = sys.output_names;
  mp.h.reserve(static_cast<std::size_t>(count) + 1);
  mp.h.push_back(sys.D);
  Eigen::MatrixXd X = sys.B;
  for (int k = 1; k <= count; ++k) {
    mp.h.push_back(sys.C * X);
    if (k < count) X = sys.A * X;
  }
  return mp;
}

ImpulseDeconvolutionResult impulse_response_from_taps(const IoData& taps, const ImpulseDeconvolutionOptions& options) {
  taps.validate();
  const Eigen::Index m = taps.inputs(), l = taps.outputs(), L = options.length;
  if (L < 1) throw std::invalid_argument("impulse_response_from_taps: need length >= 1");
  if (m < 1) throw std::invalid_argument("impulse_response_from_taps: need at least one force input");
  if (!(options.regularization >= 0.0) || !std::isfinite(options.regularization))
    throw std::invalid_argument("impulse_response_from_taps: need regularization >= 0");
  const Eigen::Index q = L * m;
  if (taps.total_samples() < q)
    throw std::invalid_argument("impulse_response_from_taps: need total samples >= length * inputs (" +
                                std::to_string(taps.total_samples()) + " < " + std::to_string(q) + ")");

  StreamingQR qr(q + l);
  for (const Experiment& e : taps.experiments) {
    const Eigen::Index N = e.samples();
    Eigen::Index k = 0;
    while (k < N) {
      const Eigen::Index take = std::min(qr.free_rows(), N - k);
      auto rows = qr.next_rows(take);
      for (Eigen::Index r = 0; r < take; ++r) {
        const Eigen::Index t = k + r;
        for (Eigen::Index s = 0; s < L; ++s) {
          if (t - s >= 0)
            rows.row(r).segment(s * m, m) = e.u.row(t - s);
          else
            rows.row(r).segment(s * m, m).setZero();
        }
        rows.row(r).tail(l) = e.y.row(t);
      }
      qr.commit_rows(take);
      k += take;
    }
  }
  const Eigen::MatrixXd R = qr.r();
  const Eigen::MatrixXd R11 = R.topLeftCorner(q, q);
  const Eigen::MatrixXd R12 = R.topRightCorner(q, l);

  ImpulseDeconvolutionResult res;
  res.equations = taps.total_samples();
  // Column norms of Phi are those of R11 (Q orthogonal).
  const Eigen::VectorXd col_norm = R11.colwise().norm().transpose();
  const double rms_col = std::sqrt(col_norm.squaredNorm() / static_cast<double>(q));
  res.lambda = options.regularization * rms_col;
  {
    Eigen::MatrixXd scaled = R11;
    for (Eigen::Index c = 0; c < q; ++c)
      if (col_norm[c] > 0.0) scaled.col(c) /= col_norm[c];
    const Eigen::VectorXd sv = Eigen::BDCSVD<Eigen::MatrixXd>(scaled).singularValues();
    res.condition = sv[sv.size() - 1] > 0.0 ? sv[0] / sv[sv.size() - 1] : std::numeric_limits<double>::infinity();
  }
  // Second QR of [R11 R12; lambda I 0]: the regularised problem, still orthogonal.
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(2 * q, q + l);
  aug.topLeftCorner(q, q) = R11;
  aug.topRightCorner(q, l) = R12;
  aug.bottomLeftCorner(q, q).diagonal().setConstant(res.lambda);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr2(aug);
  const Eigen::MatrixXd T = qr2.matrixQR().topRows(q + l).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd T11 = T.topLeftCorner(q, q);
  const double tmax = T11.diagonal().cwiseAbs().maxCoeff();
  if (!(tmax > 0.0) || T11.diagonal().cwiseAbs().minCoeff() <= 1e-14 * tmax)
    throw NumericalError("impulse_response_from_taps: the (regularised) deconvolution is singular: the forces do not excite "
                         "every lag; increase regularization or check the force channels");
  const Eigen::MatrixXd theta = T11.triangularView<Eigen::Upper>().solve(T.topRightCorner(q, l));
  // Residual of the unregularised fit: ||R11 theta - R12||^2 + ||R22||^2.
  const double rss = (R11 * theta - R12).squaredNorm() + R.bottomRightCorner(l, l).squaredNorm();
  res.residual_rms = std::sqrt(rss / static_cast<double>(res.equations * l));

  MarkovParameters& mp = res.markov;
  mp.Ts = taps.Ts;
  mp.input_names = taps.input_names;
  mp.output_names = taps.output_names;
  mp.h.assign(static_cast<std::size_t>(L), Eigen::MatrixXd(l, m));
  for (Eigen::Index s = 0; s < L; ++s) mp.h[static_cast<std::size_t>(s)] = theta.middleRows(s * m, m).transpose();

  // Tail: the largest ||h[s]|| among the last tenth (one sample may sit at a zero
  // crossing of a ringing mode).
  double hmax = 0.0, tail = 0.0;
  for (Eigen::Index s = 0; s < L; ++s) {
    const double nrm = mp.h[static_cast<std::size_t>(s)].norm();
    hmax = std::max(hmax, nrm);
    if (s >= L - std::max<Eigen::Index>(1, L / 10)) tail = std::max(tail, nrm);
  }
  if (L >= 8 && hmax > 0.0 && tail > 0.05 * hmax)
    res.warnings.push_back("impulse response has not decayed within " + std::to_string(L) + " samples (tail/peak = " +
                           format_number(tail / hmax) + "): increase length");
  if (res.condition > 1e8)
    res.warnings.push_back("ill-conditioned deconvolution (cond = " + format_number(res.condition) +
                           "): the force has little content in part of the band; the regularisation decides there");
  return res;
}

}  // namespace sysid
