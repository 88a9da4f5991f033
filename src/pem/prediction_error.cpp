// Implementation of pem/prediction_error.hpp (method and references in the header):
// pem() itself, which scales the records, picks the start(s), races them and runs
// Levenberg-Marquardt (core/levenberg_marquardt.hpp) on the prediction-error cost.
// The pieces: polynomial_utilities.cpp (parameter vector, roots, stability),
// pem_jacobian.cpp (prediction errors, cost, the R factor of [J eps]),
// variable_projection.cpp, pem_starts.cpp (initial values), pem_problem.cpp (the
// cost as the solver's Problem); internal headers in src/pem/detail/.
#include <sysid/core/column_scaled_condition.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/core/levenberg_marquardt.hpp>
#include <sysid/core/parallel_for.hpp>
#include <sysid/pem/arx.hpp>
#include <sysid/pem/lagged_regression.hpp>
#include <sysid/pem/prediction_error.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "pem/detail/pem_jacobian.hpp"
#include "pem/detail/pem_problem.hpp"
#include "pem/detail/pem_starts.hpp"

namespace sysid {

PemResult pem(IoData data, const PemOptions& options) {
  using namespace detail::pem_impl;
  data.validate();
  const Eigen::Index m = data.inputs(), l = data.outputs();
  if (options.output < 0 || options.output >= l) throw std::invalid_argument("pem: output index out of range");
  if (options.na < 0 || options.nc < 0 || options.nd < 0) throw std::invalid_argument("pem: need na, nc, nd >= 0");
  if (static_cast<Eigen::Index>(options.nb.size()) != m)
    throw std::invalid_argument("pem: need one nb per input (" + std::to_string(options.nb.size()) + " given for " +
                                std::to_string(m) + " inputs)");
  std::vector<int> nf = options.nf.empty() ? std::vector<int>(static_cast<std::size_t>(m), 0) : options.nf;
  if (static_cast<Eigen::Index>(nf.size()) != m) throw std::invalid_argument("pem: need one nf per input");
  for (Eigen::Index i = 0; i < m; ++i)
    if (options.nb[static_cast<std::size_t>(i)] < 0 || nf[static_cast<std::size_t>(i)] < 0)
      throw std::invalid_argument("pem: need nb, nf >= 0");
  const std::vector<int> nk = detail::input_delays(options.nk, m);
  const bool has_f = std::any_of(nf.begin(), nf.end(), [](int k) { return k > 0; });
  if (has_f && options.na > 0) throw std::invalid_argument("pem: an A polynomial together with F is not supported (use na = 0)");
  if (options.max_iterations < 0) throw std::invalid_argument("pem: need max_iterations >= 0");

  PemResult res;
  res.structure = structure_name(options.na, options.nb, options.nc, options.nd, nf);
  std::tie(res.input_offset, res.output_offset) = detail::remove_means_if(data, options.remove_means);

  // Scaled records of the chosen output.
  const double total = static_cast<double>(data.total_samples());
  Eigen::VectorXd su = Eigen::VectorXd::Zero(m);
  double sy = 0;
  for (const auto& e : data.experiments) {
    su += e.u.colwise().squaredNorm().transpose();
    sy += e.y.col(options.output).squaredNorm();
  }
  su = (su / total).cwiseSqrt();
  sy = std::sqrt(sy / total);
  if (!(sy > 0)) throw DataError("pem: output '" + data.output_name(options.output) + "' is constant");
  for (Eigen::Index i = 0; i < m; ++i)
    if (!(su(i) > 0)) throw DataError("pem: input '" + data.input_name(i) + "' is constant: it does not excite the system");
  std::vector<ScaledRecord> records;
  for (const auto& e : data.experiments)
    records.push_back({e.u * su.cwiseInverse().asDiagonal(), e.y.col(options.output) / sy});

  PolynomialModel model;
  model.Ts = data.Ts;
  model.A = Eigen::VectorXd::Zero(options.na + 1);
  model.A(0) = 1.0;
  model.C = Eigen::VectorXd::Zero(options.nc + 1);
  model.C(0) = 1.0;
  model.D = Eigen::VectorXd::Zero(options.nd + 1);
  model.D(0) = 1.0;
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto k = static_cast<std::size_t>(i);
    model.B.push_back(Eigen::VectorXd::Zero(options.nb[k]));
    model.nk.push_back(nk[k]);
    model.F.push_back(Eigen::VectorXd::Zero(nf[k] + 1));
    model.F.back()(0) = 1.0;
  }
  const Eigen::Index p = pack_parameters(model).size();
  if (p == 0) throw std::invalid_argument("pem: need at least one parameter");
  if (static_cast<double>(p) >= total) throw std::invalid_argument("pem: more parameters than samples");

  // Initial values and Levenberg-Marquardt.
  LevenbergMarquardt::Summary run;
  if (has_f) {
    output_error_start(model, records, options.steiglitz_mcbride_iterations, res.warnings);
    run = levenberg_marquardt(model, records, p, options);
  } else if (options.nc > 0) {
    const bool armax = options.na > 0 && m > 0;
    if (!armax && options.start != PemStart::automatic && options.start != PemStart::hannan_rissanen)
      throw std::invalid_argument("pem: the output-error and subspace starts need an ARMAX structure (na > 0 and an input)");
    std::vector<PemStart> starts{options.start};
    if (options.start == PemStart::automatic)
      starts = armax ? std::vector<PemStart>{PemStart::subspace, PemStart::hannan_rissanen}
                     : std::vector<PemStart>{PemStart::hannan_rissanen};
    // Several starts are raced a few iterations each, in step: every round is
    // one iteration of each running start, the starts on the machine's cores,
    // so the outcome does not depend on timing. The race ends after `trial`
    // rounds, or earlier once a start has converged below every start still
    // running (it sits at a local minimum to working precision that the others
    // have not reached in as many iterations; with variable projection the
    // subspace start converges on the Par2 ARMAX in 6, while the
    // Hannan-Rissanen start, at twice its cost, would take 10 trial rounds).
    // The lowest cost (the first in start order at a tie) goes on to the full
    // iteration budget; a full run from each start would multiply the time.
    const int trial = starts.size() > 1 ? std::min(options.max_iterations, 10) : options.max_iterations;
    struct Racer {
      PolynomialModel model;
      std::string name;
      std::optional<PemProblem> problem;     // holds a reference to `model`: racers never move
      std::optional<LevenbergMarquardt> lm;  // holds a reference to `problem`
      bool running() const { return lm && !lm->ended(); }
    };
    std::vector<Racer> racers(starts.size());
    parallel_for(starts.size(), [&](std::size_t k) {
      Racer& o = racers[k];
      o.model = model;
      const PemStart start = starts[k];
      if (start == PemStart::hannan_rissanen) {
        hannan_rissanen(o.model, records, hannan_rissanen_order(options, total));
        o.name = "hannan-rissanen";
      } else if (start == PemStart::subspace && armax_subspace_start(o.model, records, options)) {
        o.name = "subspace";
      } else if ((start == PemStart::output_error || options.start == PemStart::automatic) &&
                 armax_output_error_start(o.model, records, options)) {
        // Under `automatic` the output-error start stands in for a failed subspace one.
        o.name = "output-error";
      } else {
        return;
      }
      o.problem.emplace(o.model, records, p, options.variable_projection);
      o.lm.emplace(*o.problem, levenberg_marquardt_options(options));
    });
    for (int round = 0; round < trial; ++round) {
      std::vector<std::size_t> running;
      for (std::size_t k = 0; k < racers.size(); ++k)
        if (racers[k].running()) running.push_back(k);
      if (running.empty()) break;
      parallel_for(running.size(), [&](std::size_t j) { racers[running[j]].lm->iterate(); });
      double lowest_running = std::numeric_limits<double>::infinity(), lowest_converged = lowest_running;
      for (const Racer& o : racers) {
        if (!o.lm) continue;
        if (o.running()) lowest_running = std::min(lowest_running, o.lm->current_cost());
        else if (o.lm->converged()) lowest_converged = std::min(lowest_converged, o.lm->current_cost());
      }
      if (lowest_converged < lowest_running) break;
    }
    Racer* winner = nullptr;
    for (Racer& o : racers)
      if (o.lm && (!winner || o.lm->current_cost() < winner->lm->current_cost())) winner = &o;
    if (!winner)
      throw NumericalError(std::string("pem: the ") + (options.start == PemStart::subspace ? "subspace" : "output-error") +
                           " start of the ARMAX model failed (its sub-fit did not succeed)");
    winner->lm->iterate_up_to(options.max_iterations);
    run = winner->lm->finish();
    model = winner->model;
    res.start = winner->name;
  } else {
    std::vector<int> nb(options.nb.begin(), options.nb.end());
    const RegressionSolution sol = arx_regression(records, options.na, nb, nk, nullptr, 0);
    Eigen::VectorXd theta = pack_parameters(model);
    theta.head(sol.theta.size()) = sol.theta;
    unpack_parameters(theta, model);
    run = levenberg_marquardt(model, records, p, options);
  }
  res.status = pem_status(run.status);
  res.termination = run.termination;
  res.iterations = run.iterations;
  res.initial_cost = run.initial_cost;
  res.final_cost = run.final_cost;
  res.cost_history = std::move(run.cost_history);
  const double cost = run.final_cost;
  const Eigen::MatrixXd& r = run.r;

  // Covariance sigma^2 (J^T J)^-1 and conditioning at the solution (scaled units).
  const Eigen::MatrixXd r11 = r.topLeftCorner(p, p).triangularView<Eigen::Upper>();
  res.condition = column_scaled_condition(r11);
  const double sigma2 = 2.0 * cost / std::max(1.0, total - static_cast<double>(p));
  const Eigen::MatrixXd r_inv = r11.completeOrthogonalDecomposition().pseudoInverse();
  Eigen::MatrixXd covariance = sigma2 * r_inv * r_inv.transpose();
  // Above ~1/u the SVD of a double R11 no longer measures the condition: the
  // semidefinite Gram factor's zero rows make it infinite, its rounding-level
  // pivots anything from 1e16 up.
  if (!(res.condition < 1e16)) {
    res.warnings.push_back("pem: the Jacobian is rank deficient to double precision at the solution: some parameters "
                           "are not determined by the data (orders too high, or common factors)");
  } else if (res.condition > 1e10) {
    std::ostringstream w;
    w << "pem: the Jacobian is ill-conditioned at the solution (condition " << std::setprecision(3) << res.condition
      << "): some parameters are poorly determined (orders too high, or common factors)";
    res.warnings.push_back(w.str());
  }

  // Back to original units: B_i scales by sy / su_i, the variance by sy^2.
  Eigen::VectorXd unit = Eigen::VectorXd::Ones(p);
  {
    Eigen::Index at = model.na();
    for (Eigen::Index i = 0; i < m; ++i) {
      const double s = sy / su(i);
      model.B[static_cast<std::size_t>(i)] *= s;
      unit.segment(at, model.nb(i)).setConstant(s);
      at += model.nb(i);
    }
  }
  res.covariance = unit.asDiagonal() * covariance * unit.asDiagonal();
  model.noise_variance = sigma2 * sy * sy;
  res.model = model;
  res.model.validate();
  return res;
}

}  // namespace sysid
