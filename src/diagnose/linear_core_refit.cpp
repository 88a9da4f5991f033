// Joint refit of a nominal's linear dynamics and its physics blocks; the method
// is documented in include/sysid/diagnose/linear_core_refit.hpp.
#include "sysid/diagnose/linear_core_refit.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "sysid/core/real_modal_form.hpp"
#include "sysid/core/errors.hpp"
#include "sysid/core/poles_zeros.hpp"
#include "sysid/core/simulate.hpp"

namespace sysid {

namespace {

/// The real modal form (core/real_modal_form.hpp) with T well enough
/// conditioned to refit in: cond(T) below 1e8.
bool well_conditioned_real_modal_form(const Eigen::MatrixXd& A, RealModalForm& form) {
  if (real_modal_form(A, form) != RealModalStatus::ok) return false;
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(form.T).singularValues();
  return sv(sv.size() - 1) > 1e-8 * sv(0);
}

/// Everything the refit varies, with its box; `apply` writes a unit-box point
/// into the model, x0 and the candidates.
struct Parameterisation {
  std::vector<FreeParameter> linear;  ///< poles, B_m, D, x0_m (names for messages only)
  RealModalForm form;
  Eigen::MatrixXd C;                  ///< fixed C_m
  Eigen::Index n = 0, m = 0, l = 0;
  double Ts = 0.0;

  /// Model and x0 from the linear part of z (its first linear.size() entries).
  void apply(const std::vector<double>& z, StateSpace& model, Eigen::VectorXd& x0) const {
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n), B(n, m), D(l, m);
    std::size_t k = 0;
    auto next = [&]() { const double v = parameter_value(linear[k], z[k]); ++k; return v; };
    for (const auto& block : form.blocks) {
      const Eigen::Index s = block.start;
      if (block.size == 1) {
        A(s, s) = next();
      } else {
        const double modulus = next(), angle = next();
        const double sigma = modulus * std::cos(angle), omega = modulus * std::sin(angle);
        A(s, s) = sigma;
        A(s, s + 1) = omega;
        A(s + 1, s) = -omega;
        A(s + 1, s + 1) = sigma;
      }
    }
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = 0; j < m; ++j) B(i, j) = next();
    for (Eigen::Index i = 0; i < l; ++i)
      for (Eigen::Index j = 0; j < m; ++j) D(i, j) = next();
    x0.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) x0(i) = next();
    model = StateSpace(A, B, C, D, Ts);
  }
};

/// Bounds of a pole's modulus: the time constant within a factor of two.
FreeParameter modulus_bounds(const std::string& name, double r) {
  if (!(r > 0.0 && r < 1.0)) return {name, r, r};  // an integrator or unstable pole stays where it is
  return {name, r * r, std::sqrt(r)};
}

FreeParameter around(const std::string& name, double value, double reach) {
  reach = std::max(reach, std::numeric_limits<double>::min());
  return {name, value - reach, value + reach};
}

}  // namespace

LinearCoreRefitResult refit_linear_core(const StateSpace& nominal, const Eigen::VectorXd& x0,
                                        const std::vector<PhysicsBlock>& fixed, const std::vector<Candidate>& candidates,
                                        const Eigen::Ref<const Eigen::MatrixXd>& u, const Eigen::Ref<const Eigen::MatrixXd>& y,
                                        Eigen::Index rows, int substeps, const LinearCoreRefitOptions& options,
                                        const std::vector<OutputQuantity>& output_quantities) {
  nominal.validate();
  const Eigen::Index n = nominal.order(), m = nominal.inputs(), l = nominal.outputs();
  if (u.rows() != y.rows() || rows <= 0 || rows > u.rows() || u.cols() != m || y.cols() != l)
    throw std::invalid_argument("refit_linear_core: need 0 < rows <= u.rows() == y.rows() and channels matching the nominal");
  if (x0.size() != 0 && x0.size() != n) throw std::invalid_argument("refit_linear_core: need x0 empty or of the model's order");
  LinearCoreRefitResult result;
  result.model = nominal;
  result.x0 = x0.size() ? x0 : Eigen::VectorXd::Zero(n);
  result.blocks = candidates;
  result.poles_before = poles(nominal);
  result.poles_after = result.poles_before;
  if (n == 0 || n > options.max_order) {
    result.warnings.push_back("the nominal's linear dynamics were not refitted: order " + std::to_string(n) +
                              (n == 0 ? "" : " exceeds " + std::to_string(options.max_order)));
    return result;
  }

  Parameterisation par;
  par.n = n;
  par.m = m;
  par.l = l;
  par.Ts = nominal.Ts;
  if (!well_conditioned_real_modal_form(nominal.A, par.form)) {
    result.warnings.push_back("the nominal's linear dynamics were not refitted: its A has no well-conditioned eigenvector basis");
    return result;
  }
  const auto lu = par.form.T.partialPivLu();
  const Eigen::MatrixXd Bm = lu.solve(nominal.B);
  par.C = nominal.C * par.form.T;
  const Eigen::VectorXd xm = lu.solve(result.x0);
  const Eigen::MatrixXd Am = lu.solve(nominal.A * par.form.T);

  // Scales: each modal state's RMS over the record (its x0 box), and the data's
  // output-per-input scale (D's box).
  const StateSpace modal(Am, Bm, Eigen::MatrixXd::Identity(n, n), Eigen::MatrixXd::Zero(n, m), nominal.Ts);
  const Eigen::MatrixXd states = simulate(modal, u.topRows(rows), xm);
  const double u_rms = std::sqrt(u.topRows(rows).squaredNorm() / static_cast<double>(rows * m));
  const double y_rms = std::sqrt(y.topRows(rows).squaredNorm() / static_cast<double>(rows * l));
  const double gain_scale = u_rms > 0 ? y_rms / u_rms : 1.0;

  // Each linear parameter with its box and its start value (the modal form
  // reproduces the nominal exactly).
  std::vector<double> start;
  auto add = [&](FreeParameter bounds, double value) {
    start.push_back(unit_coordinate(bounds, value));
    par.linear.push_back(std::move(bounds));
  };
  for (const auto& block : par.form.blocks) {
    const Eigen::Index s = block.start;
    if (block.size == 1) {
      add(modulus_bounds("pole", Am(s, s)), Am(s, s));
    } else {
      const double sigma = Am(s, s), omega = Am(s, s + 1);
      const double r = std::hypot(sigma, omega), angle = std::atan2(omega, sigma);
      add(modulus_bounds("pole modulus", r), r);
      add({"pole angle", 0.75 * angle, std::min(1.25 * angle, std::numbers::pi)}, angle);
    }
  }
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < m; ++j)
      add(around("B", Bm(i, j), 3.0 * std::abs(Bm(i, j)) + 0.3 * Bm.row(i).cwiseAbs().maxCoeff()), Bm(i, j));
  for (Eigen::Index i = 0; i < l; ++i)
    for (Eigen::Index j = 0; j < m; ++j)
      add(around("D", nominal.D(i, j), 2.0 * std::abs(nominal.D(i, j)) + 0.5 * gain_scale), nominal.D(i, j));
  for (Eigen::Index i = 0; i < n; ++i) {
    const double state_rms = std::sqrt(states.col(i).squaredNorm() / static_cast<double>(rows));
    add(around("x0", xm(i), 2.0 * std::abs(xm(i)) + 3.0 * state_rms), xm(i));
  }
  // A store's pole is the nominal's pole of that store (the block hands the
  // nominal the input that makes it reproduce the store's level): tied to one of
  // the nominal's real poles, not a separate parameter — two poles for one store
  // would trade off against the limit. Which pole is the store is not known (the
  // upper tank may be the faster one): every real pole is tried, the best kept.
  std::vector<Eigen::Index> real_pole_states;
  for (const auto& block : par.form.blocks)
    if (block.size == 1) real_pole_states.push_back(block.start);
  std::vector<std::size_t> stores;
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (candidates[k].block.kind == "saturation" && candidates[k].block.param("storage_pole") > 0.0 && !real_pole_states.empty())
      stores.push_back(k);
  std::size_t assignments = 1;
  for (std::size_t k = 0; k < stores.size() && assignments <= 16; ++k) assignments *= real_pole_states.size();
  if (assignments > 16) {
    result.warnings.push_back("the nominal's linear dynamics were not refitted: too many ways to place its stores");
    return result;
  }

  // Never worse than the start as given (a store's own pole, untied, is not in
  // the tied parameterisation): a refit is kept only when it beats that.
  result.start_cost = simulation_cost(AugmentedSimulator(nominal, substeps, x0, output_quantities), combine_blocks(fixed, candidates), u, y, rows);
  const std::vector<double> linear_start = start;
  double best_cost = result.start_cost;
  for (std::size_t assignment = 0; assignment < assignments; ++assignment) {
    std::vector<Candidate> working = candidates;
    std::vector<std::pair<std::size_t, Eigen::Index>> tied;  ///< (candidate, state of its real pole)
    std::size_t code = assignment;
    for (std::size_t k : stores) {
      const Eigen::Index state = real_pole_states[code % real_pole_states.size()];
      code /= real_pole_states.size();
      std::erase_if(working[k].free, [](const FreeParameter& p) { return p.name == "storage_pole"; });
      working[k].block.params["storage_pole"] = Am(state, state);
      tied.emplace_back(k, state);
    }
    start = linear_start;
    for (const auto& c : working)
      for (const auto& p : c.free) start.push_back(unit_coordinate(p, c.block.param(p.name)));

    StateSpace model;
    Eigen::VectorXd x0_model;
    auto set = [&](const std::vector<double>& z) {
      par.apply(z, model, x0_model);
      std::size_t k = par.linear.size();
      for (auto& c : working)
        for (const auto& p : c.free) c.block.params[p.name] = parameter_value(p, z[k++]);
      for (const auto& [candidate, state] : tied) working[candidate].block.params["storage_pole"] = model.A(state, state);
    };
    const std::function<double(const std::vector<double>&)> cost = [&](const std::vector<double>& z) {
      set(z);
      try {
        const AugmentedSimulator simulator(model, substeps, x0_model, output_quantities);
        return simulation_cost(simulator, combine_blocks(fixed, working), u, y, rows);
      } catch (const std::invalid_argument&) {
        return std::numeric_limits<double>::infinity();
      } catch (const NumericalError&) {
        return std::numeric_limits<double>::infinity();
      }
    };
    const UnitBoxFit fit = minimise_in_unit_box(cost, start, 0, options.local_evaluations, options.relative_tolerance);
    result.evaluations += fit.evaluations;
    if (!(fit.cost < best_cost)) continue;
    best_cost = fit.cost;
    set(fit.z);
    result.model = model;
    result.model.input_names = nominal.input_names;
    result.model.output_names = nominal.output_names;
    result.x0 = x0_model;
    result.blocks = working;
    // The caller's free lists (with storage_pole) stay as they were.
    for (std::size_t k = 0; k < result.blocks.size(); ++k) result.blocks[k].free = candidates[k].free;
  }
  result.cost = best_cost;
  result.refitted = true;
  result.poles_after = poles(result.model);
  return result;
}

}  // namespace sysid
