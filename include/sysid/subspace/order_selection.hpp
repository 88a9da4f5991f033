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
/// Preconditions: singular values sorted descending, 1 <= max_order < size.
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

/// Bauer's SVC on canonical correlations (CVA singular values); samples = Hankel columns.
inline OrderChoice choose_order_by_svc(const Eigen::VectorXd& sv, int max_order, Eigen::Index samples, Eigen::Index outputs,
                                       Eigen::Index inputs) {
  const int top = std::min<int>(max_order, static_cast<int>(sv.size()) - 1);
  if (top < 1 || samples < 2) throw std::invalid_argument("order selection: need max_order >= 1 and samples >= 2");
  OrderChoice best;
  best.score = std::numeric_limits<double>::infinity();
  const double penalty = std::log(static_cast<double>(samples)) / static_cast<double>(samples);
  for (int n = 0; n <= top; ++n) {
    const double next = std::min(1.0, sv(n));
    // d(n) = 2 n l + n m parameters of (A, B, C) beyond the trivial ones (Bauer 2001, eq. 7 uses 2 n s).
    const double score = next * next + penalty * static_cast<double>(n * (2 * outputs + inputs));
    if (score < best.score) {
      best.score = score;
      best.order = n;
    }
  }
  best.rule = "Bauer's SVC criterion (canonical correlations, penalty log(N)/N): n = " + std::to_string(best.order);
  return best;
}

}  // namespace sysid
