// Implementation of realization/era.hpp (method and references in the header).
// Compiled once into libsysid: the divide-and-conquer SVD is heavy to instantiate.
#include <sysid/core/errors.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/realization/era.hpp>
#include <sysid/subspace/order_selection.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

namespace {

/// Column-wise stacking of several experiments' Markov parameters (same l, Ts).
MarkovParameters stack_markov(const std::vector<MarkovParameters>& experiments, std::vector<std::string>& warnings) {
  if (experiments.empty()) throw std::invalid_argument("era: need at least one set of Markov parameters");
  for (const MarkovParameters& e : experiments) e.validate();
  const MarkovParameters& first = experiments.front();
  if (experiments.size() == 1) return first;
  const Eigen::Index l = first.outputs();
  std::size_t count = first.h.size();
  Eigen::Index m_total = 0;
  for (const MarkovParameters& e : experiments) {
    if (e.outputs() != l)
      throw std::invalid_argument("era: experiments must have the same number of outputs (" + std::to_string(e.outputs()) +
                                  " != " + std::to_string(l) + ")");
    if (std::abs(e.Ts - first.Ts) > 1e-9 * first.Ts) throw std::invalid_argument("era: experiments must have the same Ts");
    count = std::min(count, e.h.size());
    m_total += e.inputs();
  }
  for (const MarkovParameters& e : experiments)
    if (e.h.size() != count) {
      warnings.push_back("experiments have different numbers of Markov parameters; the first " + std::to_string(count) +
                         " of each are used");
      break;
    }
  MarkovParameters out;
  out.Ts = first.Ts;
  out.output_names = first.output_names;
  bool all_named = true;
  for (const MarkovParameters& e : experiments) all_named = all_named && !e.input_names.empty();
  out.h.assign(count, Eigen::MatrixXd(l, m_total));
  Eigen::Index c = 0;
  for (std::size_t x = 0; x < experiments.size(); ++x) {
    const MarkovParameters& e = experiments[x];
    for (std::size_t k = 0; k < count; ++k) out.h[k].middleCols(c, e.inputs()) = e.h[k];
    for (Eigen::Index j = 0; j < e.inputs(); ++j)
      out.input_names.push_back(all_named ? e.input_names[static_cast<std::size_t>(j)]
                                          : e.input_name(j) + "@" + std::to_string(x + 1));
    c += e.inputs();
  }
  if (!first.output_names.empty())
    for (const MarkovParameters& e : experiments)
      if (e.output_names != first.output_names) {
        warnings.push_back("experiments name their outputs differently; the names of the first are used");
        break;
      }
  return out;
}

}  // namespace

EraResult era(const std::vector<MarkovParameters>& experiments, const EraOptions& options) {
  EraResult res;
  const MarkovParameters mp = stack_markov(experiments, res.warnings);
  const Eigen::Index l = mp.outputs(), m = mp.inputs();
  const int M = static_cast<int>(mp.h.size()) - 1;
  if (M < 2)
    throw std::invalid_argument("era: need at least 3 Markov parameters h[0..2] (alpha + beta <= M with alpha, beta >= 1)");
  if (options.row_blocks < 0 || options.column_blocks < 0)
    throw std::invalid_argument("era: need row_blocks >= 0 and column_blocks >= 0");
  if (options.order < 0) throw std::invalid_argument("era: need order >= 0");
  if (options.max_order < 0) throw std::invalid_argument("era: need max_order >= 0");
  if (options.rule == EraOrderRule::threshold && !(options.threshold > 0.0 && options.threshold < 1.0))
    throw std::invalid_argument("era: need 0 < threshold < 1");
  int alpha = options.row_blocks, beta = options.column_blocks;
  if (alpha == 0 && beta == 0) {
    alpha = static_cast<int>(std::lround(static_cast<double>(M) * static_cast<double>(m) / static_cast<double>(l + m)));
    alpha = std::clamp(alpha, 1, M - 1);
    beta = M - alpha;
  } else if (alpha == 0) {
    alpha = M - beta;
  } else if (beta == 0) {
    beta = M - alpha;
  }
  if (alpha < 1 || beta < 1 || alpha + beta > M)
    throw std::invalid_argument("era: need alpha >= 1, beta >= 1 and alpha + beta <= M = " + std::to_string(M) +
                                " (alpha = " + std::to_string(alpha) + ", beta = " + std::to_string(beta) + ")");
  res.row_blocks = alpha;
  res.column_blocks = beta;
  const Eigen::Index rows = alpha * l, cols = beta * m;
  const int rank_cap = static_cast<int>(std::min(rows, cols));
  if (options.order > rank_cap)
    throw std::invalid_argument("era: need order <= min(alpha l, beta m) = " + std::to_string(rank_cap) +
                                " (too few Markov parameters for order " + std::to_string(options.order) +
                                "; supply more or raise alpha/beta)");

  Eigen::MatrixXd H0(rows, cols), H1(rows, cols);
  for (int i = 0; i < alpha; ++i)
    for (int j = 0; j < beta; ++j) {
      H0.block(i * l, j * m, l, m) = mp.h[static_cast<std::size_t>(i + j + 1)];
      H1.block(i * l, j * m, l, m) = mp.h[static_cast<std::size_t>(i + j + 2)];
    }
  Eigen::BDCSVD<Eigen::MatrixXd> svd(H0, Eigen::ComputeThinU | Eigen::ComputeThinV);
  res.singular_values = svd.singularValues();
  const Eigen::VectorXd& sv = res.singular_values;
  if (!(sv[0] > 0.0))
    throw std::invalid_argument("era: all Markov parameters h[1..] are zero (no response to the input): nothing to realise");

  int n = options.order;
  if (n > 0) {
    res.order_rule = "given by the user";
  } else {
    const int top = options.max_order > 0 ? std::min(options.max_order, rank_cap - 1) : rank_cap - 1;
    if (top < 1)
      throw std::invalid_argument("era: " + std::to_string(M + 1) + " Markov parameters give a Hankel matrix of " +
                                  std::to_string(rows) + " x " + std::to_string(cols) +
                                  ", too small to choose an order (that needs min(alpha l, beta m) >= 2): give the order, "
                                  "or a longer impulse response");
    if (options.rule == EraOrderRule::gap) {
      const OrderChoice choice = choose_order_by_gap(sv, top);
      n = choice.order;
      res.order_rule = choice.rule;
    } else {
      n = 0;
      while (n < top && sv[n] > options.threshold * sv[0]) ++n;
      n = std::max(n, 1);
      res.order_rule = "threshold: " + std::to_string(n) + " singular values above " + std::to_string(options.threshold) +
                       " * sigma_1 (searched orders 1.." + std::to_string(top) + ")";
    }
  }
  res.order = n;
  if (n < static_cast<int>(sv.size()) && sv[n] > 0.0 && sv[n - 1] / sv[n] < 10.0)
    res.warnings.push_back("weak order decision: sigma_" + std::to_string(n) + " / sigma_" + std::to_string(n + 1) + " = " +
                           std::to_string(sv[n - 1] / sv[n]) + " (< 10)");
  if (!(sv[n - 1] > 0.0))
    throw NumericalError("era: H(0) has rank below the order " + std::to_string(n) + "; choose a smaller order");

  const Eigen::ArrayXd s_half = sv.head(n).array().sqrt();
  const Eigen::MatrixXd Un = svd.matrixU().leftCols(n);
  const Eigen::MatrixXd Vn = svd.matrixV().leftCols(n);
  // Scaling rows/columns by S^(-1/2) instead of forming inverse matrices.
  Eigen::MatrixXd A = Un.transpose() * H1 * Vn;
  A = s_half.inverse().matrix().asDiagonal() * A * s_half.inverse().matrix().asDiagonal();
  const Eigen::MatrixXd B = s_half.matrix().asDiagonal() * Vn.topRows(m).transpose();
  const Eigen::MatrixXd C = Un.topRows(l) * s_half.matrix().asDiagonal();
  res.model = StateSpace(A, B, C, mp.h[0], mp.Ts);
  res.model.input_names = mp.input_names;
  res.model.output_names = mp.output_names;

  const Eigen::VectorXcd z = poles(res.model);
  int unstable = 0;
  for (Eigen::Index i = 0; i < z.size(); ++i)
    if (std::abs(z[i]) >= 1.0) ++unstable;
  if (unstable > 0) {
    // A truly unstable system has growing Markov parameters; a stable one realised
    // unstably points at the data or the order.
    const std::size_t quarter = std::max<std::size_t>(1, mp.h.size() / 4);
    double early = 0.0, late = 0.0;
    for (std::size_t k = 1; k <= quarter && k < mp.h.size(); ++k) early += mp.h[k].squaredNorm();
    for (std::size_t k = mp.h.size() - quarter; k < mp.h.size(); ++k) late += mp.h[k].squaredNorm();
    res.warnings.push_back(std::to_string(unstable) + " unstable pole(s) (|z| >= 1) in the realisation: " +
                           (late > early ? "the Markov parameters grow (last quarter " + std::to_string(std::sqrt(late / early)) +
                                               " times the first in norm), so the system itself looks unstable"
                                         : "noisy or truncated Markov parameters, or too high an order"));
  }
  return res;
}

EraResult era(const MarkovParameters& markov, const EraOptions& options) {
  return era(std::vector<MarkovParameters>{markov}, options);
}

}  // namespace sysid
