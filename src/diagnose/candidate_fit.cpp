// NLopt fitting of physics-block parameters; see include/sysid/diagnose/candidate_fit.hpp.
#include "sysid/diagnose/candidate_fit.hpp"

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

namespace sysid {

double unit_coordinate(const FreeParameter& p, double value) {
  const double v = std::clamp(value, p.lower, p.upper);
  if (p.upper == p.lower) return 0.5;
  if (p.log_scale) return (std::log(v) - std::log(p.lower)) / (std::log(p.upper) - std::log(p.lower));
  return (v - p.lower) / (p.upper - p.lower);
}

double parameter_value(const FreeParameter& p, double z) {
  z = std::clamp(z, 0.0, 1.0);
  if (p.log_scale) return std::exp(std::log(p.lower) + z * (std::log(p.upper) - std::log(p.lower)));
  return p.lower + z * (p.upper - p.lower);
}

namespace {

/// The cost as NLopt sees it, keeping the best point evaluated: NLopt's own
/// result is not always the best it saw (a failed trust region, round-off).
struct BoxProblem {
  const std::function<double(const std::vector<double>&)>* cost;
  UnitBoxFit best;

  double evaluate(const std::vector<double>& z) {
    ++best.evaluations;
    double value = (*cost)(z);
    if (!std::isfinite(value)) value = 1e30;  // a diverging simulation: worse than anything
    if (value < best.cost) {
      best.cost = value;
      best.z = z;
    }
    return value;
  }
};

double objective(const std::vector<double>& z, std::vector<double>& /*grad*/, void* data) {
  return static_cast<BoxProblem*>(data)->evaluate(z);
}

void run(nlopt::algorithm algorithm, BoxProblem& problem, std::vector<double> z, int evaluations, double tolerance) {
  if (evaluations <= 0 || z.empty()) return;
  nlopt::opt opt(algorithm, static_cast<unsigned>(z.size()));
  opt.set_lower_bounds(std::vector<double>(z.size(), 0.0));
  opt.set_upper_bounds(std::vector<double>(z.size(), 1.0));
  opt.set_min_objective(objective, &problem);
  opt.set_maxeval(evaluations);
  if (tolerance > 0) opt.set_ftol_rel(tolerance);
  if (algorithm == nlopt::LN_BOBYQA) opt.set_initial_step(0.05);
  double value = 0.0;
  try {
    opt.optimize(z, value);
  } catch (const nlopt::roundoff_limited&) {
    // The best point so far is kept in BoxProblem; round-off is not a failure here.
  } catch (const std::runtime_error&) {
    // NLopt's generic failure (e.g. BOBYQA's trust region collapsing on a flat
    // cost): the best evaluated point stands.
  }
}

}  // namespace

UnitBoxFit minimise_in_unit_box(const std::function<double(const std::vector<double>&)>& cost, const std::vector<double>& start,
                                int global_evaluations, int local_evaluations, double relative_tolerance) {
  BoxProblem problem{&cost, {}};
  problem.best.cost = std::numeric_limits<double>::infinity();
  problem.best.start_cost = problem.evaluate(start);
  problem.best.z = start;
  // Global stage: DIRECT-L samples the whole box, so a start in the wrong basin
  // (a delay of 1 instead of 2 samples) does not trap the fit.
  run(nlopt::GN_DIRECT_L, problem, start, global_evaluations, 0.0);
  run(nlopt::LN_BOBYQA, problem, problem.best.z, local_evaluations, relative_tolerance);
  return problem.best;
}

std::vector<PhysicsBlock> combine_blocks(const std::vector<PhysicsBlock>& fixed, const std::vector<Candidate>& candidates) {
  std::vector<PhysicsBlock> blocks = fixed;
  for (const auto& c : candidates) blocks.push_back(c.block);
  return blocks;
}

double simulation_cost(const AugmentedSimulator& simulator, const std::vector<PhysicsBlock>& blocks,
                       const Eigen::Ref<const Eigen::MatrixXd>& u, const Eigen::Ref<const Eigen::MatrixXd>& y,
                       Eigen::Index rows) {
  const Eigen::MatrixXd y_hat = simulator.simulate(blocks, u, rows);
  double cost = 0.0;
  for (Eigen::Index i = 0; i < y.cols(); ++i) {
    const auto yi = y.col(i).head(rows);
    const double variance = (yi.array() - yi.mean()).square().sum();
    cost += (yi - y_hat.col(i)).squaredNorm() / std::max(variance, std::numeric_limits<double>::min());
  }
  return cost / static_cast<double>(y.cols());
}

CandidateFitResult fit_candidates(const AugmentedSimulator& simulator, const std::vector<PhysicsBlock>& fixed,
                                  std::vector<Candidate> candidates, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                  const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::Index rows,
                                  const CandidateFitOptions& options) {
  if (u.rows() != y.rows() || rows <= 0 || rows > u.rows())
    throw std::invalid_argument("fit_candidates: need 0 < rows <= u.rows() == y.rows()");
  std::vector<double> start;
  for (const auto& c : candidates)
    for (const auto& p : c.free) {
      if (!(p.lower <= p.upper)) throw std::invalid_argument("fit_candidates: " + p.name + ": need lower <= upper");
      if (p.log_scale && !(p.lower > 0.0)) throw std::invalid_argument("fit_candidates: " + p.name + ": log scale needs lower > 0");
      start.push_back(unit_coordinate(p, c.block.param(p.name)));
    }
  auto set = [&candidates](const std::vector<double>& z) {
    std::size_t k = 0;
    for (auto& c : candidates)
      for (const auto& p : c.free) c.block.params[p.name] = parameter_value(p, z[k++]);
  };
  const std::function<double(const std::vector<double>&)> cost = [&](const std::vector<double>& z) {
    set(z);
    try {
      return simulation_cost(simulator, combine_blocks(fixed, candidates), u, y, rows);
    } catch (const std::invalid_argument&) {
      return std::numeric_limits<double>::infinity();  // an inadmissible corner of the box
    }
  };
  const auto dimension = static_cast<int>(start.size());
  const UnitBoxFit fit = minimise_in_unit_box(cost, start, options.global_evaluations_per_parameter * dimension,
                                              options.local_evaluations, options.relative_tolerance);
  set(fit.z);
  CandidateFitResult result;
  result.fitted = candidates;
  result.cost = fit.cost;
  result.start_cost = fit.start_cost;
  result.evaluations = fit.evaluations;
  return result;
}

}  // namespace sysid
