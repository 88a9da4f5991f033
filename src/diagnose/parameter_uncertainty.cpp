// Sandwich (Newey-West) standard errors of fitted physics parameters; see
// include/sysid/diagnose/parameter_uncertainty.hpp.
#include "sysid/diagnose/parameter_uncertainty.hpp"
#include "sysid/core/format_number.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace sysid {

namespace {

constexpr double kNoEffect = 1e-10;       // a step changing the weighted simulation by less than this (relative): no effect
constexpr double kNullComponent = 1e-3;   // a parameter with more than this in the null space is not identifiable

void check_arguments(const AugmentedSimulator& simulator, const std::vector<Candidate>& fitted,
                     const Eigen::Ref<const Eigen::MatrixXd>& u, const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::Index rows,
                     const ParameterUncertaintyOptions& o) {
  const std::string where = "parameter_uncertainty: ";
  if (o.max_correlation_lag < 0) throw std::invalid_argument(where + "need max_correlation_lag >= 0");
  if (!(o.relative_step > 0.0 && o.relative_step <= 0.25)) throw std::invalid_argument(where + "need 0 < relative_step <= 0.25");
  if (!(o.rank_tolerance > 0.0 && o.rank_tolerance < 1.0)) throw std::invalid_argument(where + "need 0 < rank_tolerance < 1");
  if (u.cols() != simulator.nominal().inputs() || y.cols() != simulator.nominal().outputs())
    throw std::invalid_argument(where + "u and y must have the nominal's inputs and outputs as columns");
  Eigen::Index p = 0;
  for (const auto& c : fitted) p += static_cast<Eigen::Index>(c.free.size());
  if (u.rows() != y.rows() || rows <= p || rows > u.rows())
    throw std::invalid_argument(where + "need free parameters < rows <= u.rows() == y.rows()");
  if (!u.topRows(rows).allFinite() || !y.topRows(rows).allFinite()) throw std::invalid_argument(where + "u and y must be finite");
  for (const auto& c : fitted) {
    const auto& kind = c.block.info().parameters;
    for (const auto& f : c.free) {
      const std::string name = c.block.kind + "." + f.name;
      if (std::find(kind.begin(), kind.end(), f.name) == kind.end())
        throw std::invalid_argument(where + name + " is not a parameter of its kind");
      if (!(f.lower <= f.upper)) throw std::invalid_argument(where + name + ": need lower <= upper");
      if (f.log_scale && !(f.lower > 0.0)) throw std::invalid_argument(where + name + ": log scale needs lower > 0");
      const double v = c.block.param(f.name), slack = 1e-9 * (f.upper - f.lower);
      if (!(v >= f.lower - slack && v <= f.upper + slack))
        throw std::invalid_argument(where + name + ": need lower <= value <= upper");
    }
  }
}

/// Weighted simulation s_i yhat_i on rows [0, rows), stacked output by output.
Eigen::VectorXd weighted_simulation(const AugmentedSimulator& simulator, const std::vector<PhysicsBlock>& blocks,
                                    const Eigen::Ref<const Eigen::MatrixXd>& u, const Eigen::VectorXd& s, Eigen::Index rows) {
  const Eigen::MatrixXd y_hat = simulator.simulate(blocks, u, rows);
  Eigen::VectorXd out(rows * y_hat.cols());
  for (Eigen::Index i = 0; i < y_hat.cols(); ++i) out.segment(i * rows, rows) = s(i) * y_hat.col(i);
  return out;
}

std::string format_value(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

}  // namespace

ParameterUncertainty parameter_uncertainty(const AugmentedSimulator& simulator, const std::vector<PhysicsBlock>& fixed,
                                           const std::vector<Candidate>& fitted, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                           const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::Index rows,
                                           const ParameterUncertaintyOptions& options) {
  check_arguments(simulator, fitted, u, y, rows, options);
  const Eigen::Index l = y.cols();
  ParameterUncertainty result;
  result.correlation_lag = std::min(options.max_correlation_lag, rows / 4);

  // The weights of simulation_cost: s_i^2 = 1 / var(y_i) (a common 1 / rows cancels).
  Eigen::VectorXd s(l);
  for (Eigen::Index i = 0; i < l; ++i) {
    const Eigen::VectorXd yi = y.col(i).head(rows);
    const double variance = (yi.array() - yi.mean()).square().mean();
    s(i) = 1.0 / std::sqrt(std::max(variance, std::numeric_limits<double>::min()));
  }
  Eigen::VectorXd y_weighted(rows * l);
  for (Eigen::Index i = 0; i < l; ++i) y_weighted.segment(i * rows, rows) = s(i) * y.col(i).head(rows);

  // The free parameters in order, and where each lives.
  struct Slot {
    std::size_t candidate;
    std::size_t index;
  };
  std::vector<Slot> slots;
  for (std::size_t c = 0; c < fitted.size(); ++c)
    for (std::size_t k = 0; k < fitted[c].free.size(); ++k) {
      slots.push_back({c, k});
      result.names.push_back(fitted[c].block.kind + "." + fitted[c].free[k].name);
    }
  const auto p = static_cast<Eigen::Index>(slots.size());
  result.standard_errors.resize(fitted.size());
  result.identifiable.assign(slots.size(), true);
  result.covariance = Eigen::MatrixXd::Zero(p, p);
  if (p == 0) return result;

  std::vector<PhysicsBlock> blocks = combine_blocks(fixed, fitted);
  const Eigen::VectorXd y_hat = weighted_simulation(simulator, blocks, u, s, rows);
  const Eigen::VectorXd r = y_weighted - y_hat;
  const double scale = y_hat.norm() + y_weighted.norm();

  // Jacobian by differences in the unit-box coordinate, in the parameters' units.
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows * l, p);
  std::vector<bool> held(slots.size(), false), no_effect(slots.size(), false);
  for (Eigen::Index j = 0; j < p; ++j) {
    const auto jj = static_cast<std::size_t>(j);
    const auto [c, k] = slots[jj];
    const FreeParameter& f = fitted[c].free[k];
    PhysicsBlock& block = blocks[fixed.size() + c];
    const double value = block.param(f.name);
    if (!(f.upper > f.lower)) {
      held[jj] = true;
      result.warnings.push_back(result.names[jj] + ": empty box (lower == upper), held: standard error 0");
      continue;
    }
    // The weighted simulation with the parameter at unit coordinate z + dz
    // (dz = 0: the fitted value); an inadmissible value gives the centre back.
    const double z = unit_coordinate(f, value), h = options.relative_step;
    auto at = [&](double dz, double& theta) -> Eigen::VectorXd {
      theta = value;
      if (dz == 0.0) return y_hat;
      const double trial = parameter_value(f, z + dz);
      block.params[f.name] = trial;
      try {
        Eigen::VectorXd out = weighted_simulation(simulator, blocks, u, s, rows);
        block.params[f.name] = value;
        theta = trial;
        return out;
      } catch (const std::invalid_argument&) {
        block.params[f.name] = value;
        return y_hat;
      }
    };
    // Central, or one-sided at a bound (h <= 0.25 leaves room on one side).
    double down = -h, up = h;
    if (z + h > 1.0) up = 0.0;
    else if (z - h < 0.0) down = 0.0;
    double theta_minus = value, theta_plus = value;
    const Eigen::VectorXd minus = at(down, theta_minus), plus = at(up, theta_plus);
    const Eigen::VectorXd change = plus - minus;
    if (!(theta_plus > theta_minus) || !change.allFinite() || !(change.norm() > kNoEffect * scale)) {
      no_effect[jj] = true;
      continue;
    }
    J.col(j) = change / (theta_plus - theta_minus);
    if (z <= 0.0 || z >= 1.0)
      result.warnings.push_back(result.names[jj] + " = " + format_value(value) +
                                " is at a bound of its box: the standard error assumes an interior optimum");
  }

  // The parameters estimated (box not empty), their columns scaled to unit norm
  // (a column without effect stays zero), QR, SVD of R:
  // (J'J)^+ = D^-1 V Sigma^-2 V' D^-1.
  std::vector<Eigen::Index> active;
  for (Eigen::Index j = 0; j < p; ++j)
    if (!held[static_cast<std::size_t>(j)]) active.push_back(j);
  const auto q = static_cast<Eigen::Index>(active.size());
  Eigen::MatrixXd Js(rows * l, q);
  Eigen::VectorXd D = Eigen::VectorXd::Ones(q);
  for (Eigen::Index a = 0; a < q; ++a) {
    const Eigen::VectorXd col = J.col(active[static_cast<std::size_t>(a)]);
    if (col.squaredNorm() > 0.0) D(a) = col.norm();
    Js.col(a) = col / D(a);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  if (q == 0) {  // every box empty: nothing estimated
    for (std::size_t c = 0; c < fitted.size(); ++c)
      for (const auto& f : fitted[c].free) result.standard_errors[c][f.name] = 0.0;
    return result;
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(Js);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(q).triangularView<Eigen::Upper>();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeFullV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  const Eigen::MatrixXd& V = svd.matrixV();
  Eigen::Index rank = 0;
  while (rank < q && sigma(rank) > options.rank_tolerance * sigma(0)) ++rank;
  result.rank = rank;
  result.condition_number = rank == q ? sigma(0) / sigma(q - 1) : inf;

  // Sum of the Bartlett-weighted autocovariances of the scores, output by output.
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(q, q);
  const Eigen::Index L = result.correlation_lag;
  for (Eigen::Index i = 0; i < l; ++i) {
    const Eigen::MatrixXd G = Js.middleRows(i * rows, rows).array().colwise() * r.segment(i * rows, rows).array();
    S.noalias() += G.transpose() * G;
    for (Eigen::Index k = 1; k <= L; ++k) {
      const double w = 1.0 - static_cast<double>(k) / static_cast<double>(L + 1);
      const Eigen::MatrixXd gamma = G.topRows(rows - k).transpose() * G.bottomRows(rows - k);
      S += w * (gamma + gamma.transpose());
    }
  }
  // The scores sum to zero at the optimum, which pulls the sample autocovariances
  // down: E[S] = (1 - b + b^2 / 3) S_true, b = L / rows (Kiefer and Vogelsang 2005).
  const double fixed_b = static_cast<double>(L) / static_cast<double>(rows);
  S /= 1.0 - fixed_b + fixed_b * fixed_b / 3.0;
  const Eigen::MatrixXd Vr = V.leftCols(rank);
  const Eigen::MatrixXd P = Vr * sigma.head(rank).array().square().inverse().matrix().asDiagonal() * Vr.transpose();
  const Eigen::MatrixXd D_inv = D.cwiseInverse().asDiagonal();
  Eigen::MatrixXd cov = D_inv * (P * S * P) * D_inv;
  cov = (0.5 * (cov + cov.transpose())).eval();

  // Parameters with a component in the null space: not identifiable.
  for (Eigen::Index a = 0; a < q; ++a) {
    const auto jj = static_cast<std::size_t>(active[static_cast<std::size_t>(a)]);
    const double null_component = rank < q ? V.row(a).tail(q - rank).norm() : 0.0;
    if (!no_effect[jj] && null_component <= kNullComponent) continue;
    result.identifiable[jj] = false;
    cov.row(a).setConstant(nan);
    cov.col(a).setConstant(nan);
    result.warnings.push_back(result.names[jj] + " is not identifiable on these data (" +
                              (no_effect[jj] ? std::string("varying it does not change the simulation")
                                             : std::string("its effect is a combination of the other parameters'")) +
                              "): standard error +inf");
  }
  for (Eigen::Index a = 0; a < q; ++a) {
    if (!result.identifiable[static_cast<std::size_t>(active[static_cast<std::size_t>(a)])]) cov(a, a) = inf;
    for (Eigen::Index b = 0; b < q; ++b)
      result.covariance(active[static_cast<std::size_t>(a)], active[static_cast<std::size_t>(b)]) = cov(a, b);
  }
  for (Eigen::Index j = 0; j < p; ++j) {
    const auto [c, k] = slots[static_cast<std::size_t>(j)];
    result.standard_errors[c][fitted[c].free[k].name] = std::sqrt(std::max(result.covariance(j, j), 0.0));
  }
  return result;
}

CandidateUncertainty candidate_uncertainty(const ParameterUncertainty& u, const std::vector<Candidate>& fitted, std::size_t k) {
  if (k >= fitted.size() || k >= u.standard_errors.size())
    throw std::invalid_argument("candidate_uncertainty: candidate index out of range");
  Eigen::Index offset = 0;
  for (std::size_t c = 0; c < k; ++c) offset += static_cast<Eigen::Index>(fitted[c].free.size());
  const auto p = static_cast<Eigen::Index>(fitted[k].free.size());
  if (offset + p > u.covariance.rows()) throw std::invalid_argument("candidate_uncertainty: the covariance does not cover the candidates");
  return {u.covariance.block(offset, offset, p, p), u.standard_errors[k]};
}

double distance_from_null(const Candidate& c, const DefiningParameter& d, const std::map<std::string, double>& standard_errors) {
  const auto se = standard_errors.find(d.name);
  const bool free = std::any_of(c.free.begin(), c.free.end(), [&](const FreeParameter& f) { return f.name == d.name; });
  if (!free || se == standard_errors.end()) return std::numeric_limits<double>::quiet_NaN();
  const double value = c.block.param(d.name);
  const double null = d.null_parameter ? c.block.param(d.null_parameter) : d.null_value;
  if (!(se->second > 0.0)) return se->second == 0.0 && value != null ? std::numeric_limits<double>::infinity() : 0.0;
  if (!std::isfinite(se->second)) return 0.0;  // not identifiable: indistinguishable from anything
  if (d.reciprocal) return value != 0.0 ? std::abs(1.0 / value) / (se->second / (value * value)) : 0.0;
  return std::abs(value - null) / se->second;
}

bool defining_parameter_differs(const Candidate& c, const std::map<std::string, double>& standard_errors, double z,
                                std::string* why) {
  bool tested = false, differs = false;
  std::string words;
  for (const DefiningParameter& d : c.block.info().defining) {
    const double distance = distance_from_null(c, d, standard_errors);
    if (std::isnan(distance)) continue;
    tested = true;
    differs = differs || distance > z;
    words += (words.empty() ? "" : ", ") + std::string(d.name) + " " + format_number(distance, 3) + " standard errors from " +
             (d.reciprocal ? "infinity" : d.null_parameter ? "the nominal's" : format_number(d.null_value, 3));
  }
  if (why) *why = tested ? words : "no defining parameter is fitted";
  return !tested || differs;
}

std::vector<DefiningParameter> insignificant_optional_terms(const Candidate& c,
                                                            const std::map<std::string, double>& standard_errors, double z) {
  std::vector<DefiningParameter> out;
  for (const DefiningParameter& d : c.block.info().optional_terms) {
    const double distance = distance_from_null(c, d, standard_errors);
    if (!std::isnan(distance) && !(distance > z)) out.push_back(d);
  }
  return out;
}

void hold_at_null(Candidate& c, const std::vector<DefiningParameter>& terms) {
  for (const DefiningParameter& d : terms) {
    c.block.params[d.name] = d.null_parameter ? c.block.param(d.null_parameter) : d.null_value;
    c.free.erase(std::remove_if(c.free.begin(), c.free.end(), [&](const FreeParameter& f) { return f.name == d.name; }),
                 c.free.end());
  }
}

}  // namespace sysid
