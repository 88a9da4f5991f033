#pragma once
/// @file
/// Purpose: ERA, the eigensystem realisation algorithm: a minimal state-space
/// model from Markov parameters (realization/markov_parameters.hpp: from an
/// FIR/LMS estimate, OKID or hammer taps), MIMO, from one or several experiments.
///
/// Method (Juang & Pappa 1985): with the block Hankel matrices (alpha block
/// rows, beta block columns, eq. 5)
///   H(k) = [h[k+1]     h[k+2]   ... h[k+beta]       ]
///          [h[k+2]     ...                          ]
///          [h[k+alpha] ...          h[k+alpha+beta-1]],   size alpha l x beta m,
/// the SVD H(0) = U S V^T truncated to the order n gives (eq. 33-35)
///   A = S_n^(-1/2) U_n^T H(1) V_n S_n^(-1/2),
///   B = first m columns of S_n^(1/2) V_n^T,
///   C = first l rows of U_n S_n^(1/2),
///   D = h[0],
/// a balanced realisation (observability and controllability Gramians of the
/// finite Hankel factors equal S_n). Several experiments with the same outputs
/// are stacked column-wise, h[k] = [h^(1)[k], h^(2)[k], ...]: the inputs of the
/// experiments become the inputs of the realisation, in order (the paper's
/// isolator workflow: one actuator excited per experiment, one SIMO estimate each).
///
/// Order: fixed (order > 0), or automatic from the Hankel singular values
/// sigma_1 >= sigma_2 >= ...: the largest gap log10(sigma_n / sigma_(n+1)) over
/// n = 1..max_order (subspace/order_selection.hpp, choose_order_by_gap), or the
/// number of sigma_i > threshold * sigma_1.
///
/// Preconditions (std::invalid_argument): the Markov parameters validate();
/// several experiments share l, Ts (relative difference <= 1e-9) and have at
/// least alpha + beta + 1 matrices each; alpha, beta >= 1 with alpha + beta <= M,
/// M = (number of matrices) - 1; 1 <= order <= min(alpha l, beta m).
/// Numerical aspects: one SVD of the alpha l x beta m matrix H(0)
/// (O(alpha l (beta m)^2), divide-and-conquer) plus O(n alpha l beta m) for A.
/// Exact Markov parameters of an order-n system give its poles to rounding
/// level when alpha l, beta m >= n (H(0) then has rank n).
///
/// References: J.-N. Juang, R. S. Pappa, "An eigensystem realization algorithm for
/// modal parameter identification and model reduction", Journal of Guidance,
/// Control, and Dynamics 8(5):620-627, 1985.
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/realization/markov_parameters.hpp>
#include <sysid/subspace/order_selection.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

enum class EraOrderRule { gap, threshold };

struct EraOptions {
  int order = 0;  ///< n > 0: fixed order; 0: automatic by `rule`
  EraOrderRule rule = EraOrderRule::gap;
  double threshold = 1e-6;  ///< threshold rule: keep sigma_i > threshold * sigma_1
  /// Largest order the automatic rules may return; 0 = min(alpha l, beta m) - 1.
  /// Set it below p l for OKID Markov parameters (see realization/okid.hpp).
  int max_order = 0;
  /// alpha (block rows) and beta (block columns) of H(0). 0 = automatic:
  /// alpha + beta = M (all Markov parameters used) with alpha l ~ beta m (a
  /// near-square Hankel matrix), alpha = max(1, round(M m_total / (l + m_total)));
  /// if only one is given the other is M minus it.
  int row_blocks = 0;
  int column_blocks = 0;
};

struct EraResult {
  StateSpace model;                 ///< balanced realisation, Ts of the Markov parameters
  Eigen::VectorXd singular_values;  ///< of H(0), descending
  int order = 0;
  int row_blocks = 0, column_blocks = 0;
  std::string order_rule;  ///< which rule chose the order and why
  std::vector<std::string> warnings;
};

namespace detail {

/// Column-wise stacking of several experiments' Markov parameters (same l, Ts).
inline MarkovParameters stack_markov(const std::vector<MarkovParameters>& experiments, std::vector<std::string>& warnings) {
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

}  // namespace detail

/// Purpose: ERA realisation from several experiments' Markov parameters stacked
/// column-wise (file comment); one experiment is the plain case.
/// Warnings: weak order decision (sigma_n / sigma_(n+1) < 10); unstable poles in
/// the realisation. (Markov parameters that have not decayed within the Hankel
/// window are no error for ERA itself, which is exact for any window when the
/// data are exact; a truncation bias arises in the estimator that produced them,
/// which warns about it.)
inline EraResult era(const std::vector<MarkovParameters>& experiments, const EraOptions& options = {}) {
  EraResult res;
  const MarkovParameters mp = detail::stack_markov(experiments, res.warnings);
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
  if (!(sv[0] > 0.0)) throw NumericalError("era: all Markov parameters h[1..] are zero; nothing to realise");

  int n = options.order;
  if (n > 0) {
    res.order_rule = "given by the user";
  } else {
    const int top = options.max_order > 0 ? std::min(options.max_order, rank_cap - 1) : rank_cap - 1;
    if (top < 1) throw std::invalid_argument("era: automatic order needs min(alpha l, beta m) >= 2");
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
  if (unstable > 0)
    res.warnings.push_back(std::to_string(unstable) + " unstable pole(s) (|z| >= 1) in the realisation: noisy or truncated "
                                                      "Markov parameters, or too high an order");
  return res;
}

/// Purpose: ERA from one set of Markov parameters.
inline EraResult era(const MarkovParameters& markov, const EraOptions& options = {}) {
  return era(std::vector<MarkovParameters>{markov}, options);
}

}  // namespace sysid
