#pragma once
/// @file
/// Purpose: choose the model order from the singular values of the weighted
/// oblique projection of subspace identification.
///
/// Method: three rules on the singular values (a fourth, n4sid's `stable`, reads
/// the stabilisation diagram: subspace/stabilization_diagram.hpp); the result says
/// which one chose the order and why.
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
///  - test: a sequential largest-root test of the canonical correlations (Roy's
///    test; T. W. Anderson, "An Introduction to Multivariate Statistical
///    Analysis", 3rd ed., sec. 12.4 and 8.6): the order is the number of
///    canonical correlations that stand above what noise gives, the k-th tested
///    against the largest correlation of independent sets of i l - k future and
///    q - k past dimensions over the regression's samples, at level 1e-3, with
///    the Tracy-Widom approximation of that largest root (core/distributions.hpp,
///    Johnstone 2008), its scale widened for the Hankel columns' dependence
///    (kHankelScaleInflation). For a system of order n the projection of the future on
///    the past has rank n whatever the horizon (the future is Gamma_i x_i plus
///    terms independent of the past), so past the true order only sampling noise
///    is left. The noise level grows with the dimensions (about
///    sqrt(i l / N) + sqrt(q / N)) instead of with a parameter count, so with
///    many outputs it does not swamp real modes.
///
/// SVC's penalty grows with n (2l + m): with many outputs and few samples it can
/// exceed every drop of sigma_{n+1}^2 even when the canonical correlations are
/// near 1 (the DaISy glass furnace, 6 outputs, 3 inputs, 1 247 samples: sigma =
/// 0.9999, 0.9987, 0.993, ... decline gradually and SVC returns 0). Whether the
/// past predicts the future at all is then a separate question, answered by
/// bartlett_zero_correlation_test below; n4sid falls back to the gap rule when
/// it does (subspace/n4sid.hpp). With tens of outputs SVC is blind even to
/// perfectly correlated modes: its penalty for n orders, n log(N)/N (2l + m),
/// exceeds 1 (the largest squared correlation) at n = N / (log(N) (2l + m)), 16
/// for 28 outputs, 2 inputs and 8 500 samples. n4sid's default rule (automatic)
/// is SVC unless the test finds an order at which SVC's penalty exceeds 1/2:
/// then the test chooses (svc_is_swamped).
///
/// Preconditions: singular values sorted descending, 1 <= max_order < size.
#include <sysid/core/distributions.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>

namespace sysid {

enum class OrderRule {
  automatic,  ///< svc, or test where SVC's penalty swamps the order the test finds (svc_is_swamped)
  svc,
  gap,
  test,
  /// the lowest order holding every physical mode of the stabilisation diagram
  /// (subspace/stabilization_diagram.hpp); n4sid only
  stabilization,
};

/// The rule's name on the command line: auto, svc, gap, test, stable.
inline const char* to_string(OrderRule rule) {
  switch (rule) {
    case OrderRule::automatic: return "auto";
    case OrderRule::svc: return "svc";
    case OrderRule::gap: return "gap";
    case OrderRule::test: return "test";
    case OrderRule::stabilization: return "stable";
  }
  return "?";
}

/// Every rule, in the order the command line lists them.
inline constexpr OrderRule kOrderRules[] = {OrderRule::automatic, OrderRule::svc, OrderRule::gap, OrderRule::test,
                                            OrderRule::stabilization};

/// The rule named `name` (to_string's names); std::invalid_argument otherwise.
inline OrderRule order_rule_from_name(const std::string& name) {
  for (const OrderRule r : kOrderRules)
    if (name == to_string(r)) return r;
  throw std::invalid_argument("unknown order rule '" + name + "' (auto, svc, gap, test or stable)");
}

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

/// The level of the sequential canonical-correlation test (the probability that
/// a noise correlation is taken for a mode at the true order, were the Hankel
/// columns independent samples).
inline constexpr double kOrderTestLevel = 1e-3;

/// The Hankel columns are not independent samples: each shares all but one of
/// its values with the next. On white-noise data (the subspace core's canonical
/// correlations of independent white inputs and outputs, 300 records per case,
/// tests/unit/subspace_order_selection.cpp repeats one) the largest correlation
/// keeps the Jacobi law's centre (median of the standardised statistic -0.4 to
/// -2.3 against Tracy-Widom's -1.27) but not its scale: its 99th percentile is
/// 3.1 to 6.2 with 2 to 28 outputs and 8 with one output and horizon 20, against
/// Tracy-Widom's 2.02. The test therefore takes the law's scale three times
/// larger: the noise level is logit^-1(mu + 3 sigma W_{1-level}), mu + 9.8 sigma
/// at level 1e-3, above every one of those 1 530 records but the one-output
/// horizon-20 case's largest (13.5).
inline constexpr double kHankelScaleInflation = 3.0;

/// The noise level of the test for the (n+1)-th correlation: the quantile of the
/// largest correlation of independent sets of the remaining dimensions at the
/// Tracy-Widom quantile `tw_quantile` (of the test's level), with the scale
/// widened by kHankelScaleInflation.
inline double correlation_noise_level(int n, Eigen::Index samples, Eigen::Index future_dims, Eigen::Index past_dims,
                                      double tw_quantile) {
  const LogitTracyWidomLaw law = largest_canonical_correlation_law(
      static_cast<double>(std::max<Eigen::Index>(future_dims - n, 1)), static_cast<double>(std::max<Eigen::Index>(past_dims - n, 1)),
      static_cast<double>(samples - n));
  const double logit = law.mu + kHankelScaleInflation * law.sigma * tw_quantile;
  return std::sqrt(1.0 / (1.0 + std::exp(-logit)));
}

/// The sequential largest-root test of the file comment. `correlations`:
/// canonical correlations, descending; samples: the regression's samples (Hankel
/// columns less the future-input rows projected out); future_dims, past_dims:
/// the dimensions of the two sets. Searches orders 0..max_order (capped by the
/// correlations there are); the rule says how far the last kept and the first
/// rejected correlation stand from the noise level.
inline OrderChoice choose_order_by_correlation_test(const Eigen::VectorXd& correlations, int max_order, Eigen::Index samples,
                                                    Eigen::Index future_dims, Eigen::Index past_dims,
                                                    double level = kOrderTestLevel) {
  const int top = std::min<int>(max_order, static_cast<int>(correlations.size()) - 1);
  if (top < 1) throw std::invalid_argument("order selection: need max_order >= 1 and 2 correlations");
  if (samples <= future_dims + past_dims)
    throw std::invalid_argument("order selection: the canonical-correlation test needs more samples than dimensions (" +
                                std::to_string(samples) + " <= " + std::to_string(future_dims + past_dims) + ")");
  OrderChoice best;
  double kept_level = 0.0, next_level = 0.0;
  const double tw_quantile = tracy_widom1_upper_quantile(level);  // one bisection, not one per order
  int n = 0;
  for (; n <= top; ++n) {
    next_level = correlation_noise_level(n, samples, future_dims, past_dims, tw_quantile);
    if (correlations(n) <= next_level) break;
    kept_level = next_level;
  }
  const bool capped = n > top;
  best.order = capped ? top : n;
  best.score = best.order > 0 ? correlations(best.order - 1) / kept_level : 0.0;
  auto fixed = [](double v) {
    std::ostringstream s;
    s << std::setprecision(3) << v;
    return s.str();
  };
  best.rule = "canonical-correlation test (largest root, level " + fixed(level) + "): ";
  if (best.order > 0)
    best.rule += "r_" + std::to_string(best.order) + " = " + fixed(correlations(best.order - 1)) + " stands above the noise level " +
                 fixed(kept_level);
  if (capped)
    best.rule += ", and so does every correlation up to the search limit " + std::to_string(top) +
                 " (the order may be higher: raise --horizon or --max-order)";
  else
    best.rule += std::string(best.order > 0 ? ", " : "") + "r_" + std::to_string(best.order + 1) + " = " +
                 fixed(correlations(best.order)) + " does not (noise level " + fixed(next_level) + ")";
  return best;
}

/// Whether SVC's penalty swamps `order` (see the file comment): its penalty for
/// that many orders exceeds half the largest possible squared correlation, so
/// SVC cannot choose it however clearly the data show it.
inline bool svc_is_swamped(int order, Eigen::Index samples, Eigen::Index outputs, Eigen::Index inputs) {
  return svc_penalty_per_order(samples, outputs, inputs) * order > 0.5;
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
