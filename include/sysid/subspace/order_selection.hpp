#pragma once
/// @file
/// Purpose: choose the model order from the singular values of the weighted
/// oblique projection of subspace identification.
///
/// Method: two rules, both reported so the user sees why an order was chosen.
///  - gap: the order n maximising log10(sigma_n / sigma_{n+1}) over 1..max_order,
///    i.e. the largest drop on the usual log-scale singular-value plot
///    (Van Overschee & De Moor 1996, sec. 4.3.2 "order by inspection of the
///    singular values", made automatic).
///  - svc: Bauer's singular-value criterion (D. Bauer, "Order estimation for
///    subspace methods", Automatica 37 (2001) 1561-1573, eq. (7)):
///    SVC(n) = sigma_{n+1}^2 + C(N) d(n) / N with d(n) = 2 n l the number of
///    parameters of the (A, C) pair... scaled to canonical correlations; C(N) = log N.
///    Valid for CVA-weighted singular values (canonical correlations in [0,1]).
/// The default `automatic` uses `gap`, because it is weighting-independent.
///
/// Preconditions: singular values sorted descending, max_order < size.
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
