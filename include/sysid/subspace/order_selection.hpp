#pragma once
/// @file
/// Purpose: choose the model order from the singular values of the weighted
/// oblique projection of subspace identification.
///
/// Method: two rules; the result says which one chose the order and why.
///  - svc (default): Bauer's singular-value criterion on the canonical
///    correlations sigma_k between future outputs (future inputs projected out)
///    and the past (D. Bauer, "Order estimation for subspace methods",
///    Automatica 37 (2001) 1561-1573, sec. 4):
///      SVC(n) = sigma_{n+1}^2 + C(N) d(n) / N,   C(N) = log N,
///    with N the number of Hankel columns and d(n) = n (2l + m) the number of
///    free parameters of (A, B, C, K) up to a similarity transform. A
///    statistical rule: a mode is kept when its canonical correlation stands
///    out of what N samples of noise would give.
///  - gap: the order n maximising log10(sigma_n / sigma_{n+1}) of the weighted
///    singular values over 1..max_order, i.e. the largest drop on the usual
///    log-scale plot (Van Overschee & De Moor 1996, sec. 4.3.2, made automatic).
///    Scale-free but blind to weak modes behind a large gap.
///
/// SVC's penalty grows with n (2l + m): with many outputs and few samples it can
/// exceed every drop of sigma_{n+1}^2 even when the canonical correlations are
/// near 1 (the DaISy glass furnace, 6 outputs, 3 inputs, 1 247 samples: sigma =
/// 0.9999, 0.9987, 0.993, ... decline gradually and SVC returns 0). Whether the
/// past predicts the future at all is then a separate question, answered by
/// bartlett_zero_correlation_test below; n4sid falls back to the gap rule when
/// it does (subspace/n4sid.hpp).
///
/// Preconditions: singular values sorted descending, 1 <= max_order < size.
#include <sysid/core/distributions.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sysid {

enum class OrderRule { gap, svc };

struct OrderChoice {
  int order = 0;
  std::string rule;    ///< human-readable: which rule and the numbers behind it
  double score = 0.0;  ///< the rule's score at the chosen order
};

inline OrderChoice choose_order_by_gap(const Eigen::VectorXd& sv, int max_order) {
  if (sv.size() < 2) throw std::invalid_argument("order selection: need at least 2 singular values");
  const int top = std::min<int>(max_order, static_cast<int>(sv.size()) - 1);
  if (top < 1) throw std::invalid_argument("order selection: need max_order >= 1");
  OrderChoice best;
  best.score = -1.0;
  const double floor = sv(0) * 1e-15;
  for (int n = 1; n <= top; ++n) {
    const double gap = std::log10(std::max(sv(n - 1), floor) / std::max(sv(n), floor));
    if (gap > best.score) {
      best.score = gap;
      best.order = n;
    }
  }
  best.rule = "largest singular-value gap: sigma_" + std::to_string(best.order) + "/sigma_" + std::to_string(best.order + 1) +
              " = " + std::to_string(std::pow(10.0, best.score)) + " (searched orders 1.." + std::to_string(top) + ")";
  return best;
}

/// What SVC adds per unit of order: C(N)/N d(1) = log(N)/N (2l + m).
inline double svc_penalty_per_order(Eigen::Index samples, Eigen::Index outputs, Eigen::Index inputs) {
  return std::log(static_cast<double>(samples)) / static_cast<double>(samples) * static_cast<double>(2 * outputs + inputs);
}

/// Bauer's SVC on canonical correlations (CVA singular values); samples = Hankel columns.
inline OrderChoice choose_order_by_svc(const Eigen::VectorXd& sv, int max_order, Eigen::Index samples, Eigen::Index outputs,
                                       Eigen::Index inputs) {
  const int top = std::min<int>(max_order, static_cast<int>(sv.size()) - 1);
  if (top < 1 || samples < 2) throw std::invalid_argument("order selection: need max_order >= 1 and samples >= 2");
  OrderChoice best;
  best.score = std::numeric_limits<double>::infinity();
  // d(n) = 2 n l + n m parameters of (A, B, C) beyond the trivial ones (Bauer 2001, eq. 7 uses 2 n s).
  const double penalty = svc_penalty_per_order(samples, outputs, inputs);
  for (int n = 0; n <= top; ++n) {
    const double next = std::min(1.0, sv(n));
    const double score = next * next + penalty * static_cast<double>(n);
    if (score < best.score) {
      best.score = score;
      best.order = n;
    }
  }
  best.rule = "Bauer's SVC criterion (canonical correlations, penalty log(N)/N): n = " + std::to_string(best.order);
  return best;
}

/// Bartlett's test that all canonical correlations between a p- and a
/// q-dimensional set are zero: X = -(N - 1 - (p + q + 1) / 2) sum_j ln(1 - sigma_j^2)
/// is approximately chi-square with p q degrees of freedom when the sets are
/// independent (M. S. Bartlett, "Further aspects of the theory of multiple
/// regression", Proc. Camb. Phil. Soc. 34 (1938) 33-40; T. W. Anderson, "An
/// Introduction to Multivariate Statistical Analysis", 3rd ed., sec. 12.4).
/// For the Hankel columns of a white-noise record the sample cross-covariances
/// have the variance of N independent samples, so the level holds there;
/// coloured noise has real past-future correlation, which the test is meant to find.
struct CanonicalCorrelationTest {
  bool valid = false;  ///< false when N - 1 - (p + q + 1) / 2 <= 0 (too few samples for the test)
  double statistic = 0, dof = 0, p_value = 1;
};

inline CanonicalCorrelationTest bartlett_zero_correlation_test(const Eigen::VectorXd& correlations, Eigen::Index samples,
                                                               Eigen::Index p, Eigen::Index q) {
  if (p < 1 || q < 1 || samples < 1) throw std::invalid_argument("bartlett_zero_correlation_test: need p, q, samples >= 1");
  CanonicalCorrelationTest t;
  const double factor = static_cast<double>(samples) - 1.0 - 0.5 * static_cast<double>(p + q + 1);
  if (!(factor > 0.0)) return t;
  double sum_log = 0.0;
  // A correlation of 1 to rounding would make the logarithm -Inf: cap it.
  for (const double c : correlations) sum_log += std::log1p(-std::min(c * c, 1.0 - 1e-15));
  t.valid = true;
  t.statistic = -factor * sum_log;
  t.dof = static_cast<double>(p * q);
  t.p_value = chi_square_sf(t.statistic, t.dof);
  return t;
}

}  // namespace sysid
