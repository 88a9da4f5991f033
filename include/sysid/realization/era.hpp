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

/// Purpose: ERA realisation from several experiments' Markov parameters stacked
/// column-wise (file comment); one experiment is the plain case.
/// Warnings: weak order decision (sigma_n / sigma_(n+1) < 10); unstable poles in
/// the realisation. (Markov parameters that have not decayed within the Hankel
/// window are no error for ERA itself, which is exact for any window when the
/// data are exact; a truncation bias arises in the estimator that produced them,
/// which warns about it.)
EraResult era(const std::vector<MarkovParameters>& experiments, const EraOptions& options = {});

/// Purpose: ERA from one set of Markov parameters.
EraResult era(const MarkovParameters& markov, const EraOptions& options = {});

}  // namespace sysid
