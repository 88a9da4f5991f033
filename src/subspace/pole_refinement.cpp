// Implementation of subspace/pole_refinement.hpp (method and references in the header).
#include <sysid/subspace/pole_refinement.hpp>

#include <sysid/core/levenberg_marquardt.hpp>
#include <sysid/core/real_modal_form.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/subspace/bdx_least_squares.hpp>

#include <algorithm>
#include <memory>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

namespace sysid {

namespace {

/// The eigenvalue parameters of a real modal form: (Re, Im) of each pair, Re of each real eigenvalue, in block order.
Eigen::VectorXd eigenvalue_parameters(const std::vector<RealModalBlock>& blocks) {
  std::vector<double> theta;
  for (const RealModalBlock& b : blocks) {
    theta.push_back(b.lambda.real());
    if (b.size == 2) theta.push_back(b.lambda.imag());
  }
  return Eigen::Map<const Eigen::VectorXd>(theta.data(), static_cast<Eigen::Index>(theta.size()));
}

/// blockdiag([lambda] or [[Re, Im], [-Im, Re]]) from the parameters (real_modal_form's convention).
Eigen::MatrixXd modal_matrix(const std::vector<RealModalBlock>& blocks, const Eigen::VectorXd& theta, Eigen::Index n) {
  Eigen::MatrixXd am = Eigen::MatrixXd::Zero(n, n);
  Eigen::Index k = 0;
  for (const RealModalBlock& b : blocks) {
    const Eigen::Index i = b.start;
    if (b.size == 2) {
      const double re = theta(k), im = theta(k + 1);
      am(i, i) = re;
      am(i, i + 1) = im;
      am(i + 1, i) = -im;
      am(i + 1, i + 1) = re;
      k += 2;
    } else {
      am(i, i) = theta(k++);
    }
  }
  return am;
}

/// Every eigenvalue strictly inside the unit circle.
bool stable(const std::vector<RealModalBlock>& blocks, const Eigen::VectorXd& theta) {
  Eigen::Index k = 0;
  for (const RealModalBlock& b : blocks) {
    const double re = theta(k), im = b.size == 2 ? theta(k + 1) : 0.0;
    if (!(re * re + im * im < 1.0)) return false;
    k += b.size;
  }
  return true;
}

/// The projected simulation error as a Levenberg-Marquardt problem.
class RefinementProblem final : public LevenbergMarquardt::Problem {
 public:
  RefinementProblem(const IoData& data, std::vector<RealModalBlock> blocks, Eigen::MatrixXd cm, Eigen::VectorXd theta,
                    Eigen::Index max_samples)
      : m_data(data), m_blocks(std::move(blocks)), m_cm(std::move(cm)), m_theta(std::move(theta)) {
    m_bdx.max_samples = max_samples;
    // Each output's residual is divided by its spread about the mean over the
    // samples used, so that 1 - ||r_i|| is its fit and the outputs weigh alike.
    // Two passes (mean, then squares about it): outputs riding on an offset lose
    // no digits to cancellation.
    const Eigen::Index l = data.outputs();
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(l);
    for (const Experiment& e : data.experiments) {
      const Eigen::Index used = std::min(e.samples(), max_samples);
      m_rows += used * l;
      sum += e.y.topRows(used).colwise().sum().transpose();
    }
    const Eigen::RowVectorXd mean = (sum / static_cast<double>(m_rows / l)).transpose();
    Eigen::VectorXd squares = Eigen::VectorXd::Zero(l);
    for (const Experiment& e : data.experiments)
      squares += (e.y.topRows(std::min(e.samples(), max_samples)).rowwise() - mean).colwise().squaredNorm().transpose();
    m_spread = squares.cwiseSqrt();
    for (Eigen::Index i = 0; i < l; ++i)
      if (!(m_spread(i) > 0.0)) m_spread(i) = 1.0;  // a constant output: its error counts in its own units
    m_residual = residual(m_theta).value_or(Eigen::VectorXd());
  }

  bool valid() const { return m_residual.size() == m_rows; }
  Eigen::Index residual_count() const override { return m_rows; }
  Eigen::Index parameter_count() const override { return m_theta.size(); }
  Eigen::VectorXd parameters() const override { return m_theta; }
  double cost() override { return 0.5 * m_residual.squaredNorm(); }

  Eigen::MatrixXd jacobian_factor() override {
    const Eigen::Index p = m_theta.size();
    Eigen::MatrixXd jr(m_rows, p + 1);
    for (Eigen::Index k = 0; k < p; ++k) {
      // Forward difference, backward when the forward point leaves the unit circle;
      // the step is small against any pole's distance to the circle that a
      // simulation error can resolve (1e-6 against 4e-3 for the Par2 28 Hz mode).
      double h = 1e-6 * std::max(std::abs(m_theta(k)), 0.1);
      Eigen::VectorXd shifted = m_theta;
      shifted(k) += h;
      if (!stable(m_blocks, shifted)) {
        h = -h;
        shifted(k) = m_theta(k) + h;
      }
      const std::optional<Eigen::VectorXd> r = residual(shifted);
      jr.col(k) = r ? Eigen::VectorXd((*r - m_residual) / h) : Eigen::VectorXd::Zero(m_rows);
    }
    jr.col(p) = m_residual;
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(jr);
    return qr.matrixQR().topRows(p + 1).triangularView<Eigen::Upper>();
  }

  bool set_candidate(const Eigen::VectorXd& x) override {
    if (!stable(m_blocks, x)) return false;
    const std::optional<Eigen::VectorXd> r = residual(x);
    if (!r) return false;
    m_candidate = x;
    m_candidate_residual = *r;
    return true;
  }
  double candidate_cost() override { return 0.5 * m_candidate_residual.squaredNorm(); }
  void accept_candidate() override {
    m_theta = m_candidate;
    m_residual = m_candidate_residual;
  }

  /// Mean fit % over the outputs at the current point.
  double fit() const {
    const Eigen::Index l = m_data.outputs();
    Eigen::VectorXd error2 = Eigen::VectorXd::Zero(l);
    Eigen::Index at = 0;
    for (const Experiment& e : m_data.experiments) {
      const Eigen::Index used = std::min(e.samples(), m_bdx.max_samples);
      for (Eigen::Index i = 0; i < l; ++i) error2(i) += m_residual.segment(at + i * used, used).squaredNorm();
      at += used * l;
    }
    return 100.0 * (1.0 - error2.array().sqrt()).mean();
  }

 private:
  /// The simulation error at eigenvalues `theta` with B, D, x0 by least squares:
  /// per experiment, output after output (each divided by its spread); empty when
  /// the regression or the simulation breaks down.
  std::optional<Eigen::VectorXd> residual(const Eigen::VectorXd& theta) const {
    const Eigen::MatrixXd am = modal_matrix(m_blocks, theta, m_cm.cols());
    try {
      const BdxLeastSquaresResult bdx = bdx_least_squares(am, m_cm, m_data, m_bdx);
      const StateSpace model(am, bdx.B, m_cm, bdx.D, m_data.Ts);
      Eigen::VectorXd r(m_rows);
      Eigen::Index at = 0;
      for (std::size_t e = 0; e < m_data.experiments.size(); ++e) {
        const Experiment& ex = m_data.experiments[e];
        const Eigen::Index used = std::min(ex.samples(), m_bdx.max_samples);
        // A is block diagonal already: the modal recursion (one 2x2 block per mode).
        simulate_blockwise_modal(model, ex.u.topRows(used), bdx.x0[e], [&](Eigen::Index k0, const Eigen::Ref<Eigen::MatrixXd>& yb) {
          for (Eigen::Index i = 0; i < yb.cols(); ++i)
            r.segment(at + i * used + k0, yb.rows()) = (ex.y.col(i).segment(k0, yb.rows()) - yb.col(i)) / m_spread(i);
        });
        at += used * m_data.outputs();
      }
      if (!r.allFinite()) return std::nullopt;
      return r;
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }

  const IoData& m_data;
  std::vector<RealModalBlock> m_blocks;
  Eigen::MatrixXd m_cm;
  Eigen::VectorXd m_theta, m_candidate;
  Eigen::VectorXd m_residual, m_candidate_residual;
  BdxLeastSquaresOptions m_bdx;
  Eigen::VectorXd m_spread;
  Eigen::Index m_rows = 0;
};

}  // namespace

double refinement_cost(Eigen::Index order, const IoData& data, Eigen::Index max_samples) {
  Eigen::Index samples = 0;
  for (const Experiment& e : data.experiments) samples += std::min(e.samples(), max_samples);
  const double columns = static_cast<double>(order * data.inputs() + data.outputs() * data.inputs() + order);
  return static_cast<double>(order) * static_cast<double>(samples) * static_cast<double>(data.outputs()) * columns * columns;
}

PoleRefinementResult refine_poles(const std::vector<PoleRefinementStart>& starts, const IoData& data,
                                  const PoleRefinementOptions& options) {
  if (starts.empty()) throw std::invalid_argument("refine_poles: need at least one start");
  struct Run {
    std::size_t start;
    RealModalForm form;
    std::unique_ptr<RefinementProblem> problem;
    std::unique_ptr<LevenbergMarquardt> solver;
    double initial_fit;
  };
  LevenbergMarquardt::Options lm;
  lm.max_iterations = options.max_iterations;
  std::vector<Run> runs;
  std::string reason;
  for (std::size_t k = 0; k < starts.size(); ++k) {
    const Eigen::MatrixXd& a = starts[k].A;
    const Eigen::MatrixXd& c = starts[k].C;
    const Eigen::Index n = a.rows();
    if (n < 1 || a.cols() != n) throw std::invalid_argument("refine_poles: need a square A of order >= 1");
    if (c.cols() != n || c.rows() != data.outputs())
      throw std::invalid_argument("refine_poles: need C with one row per output and n columns");
    double condition = 0;
    std::optional<RealModalForm> form = conditioned_real_modal_form(a, options.modal_condition_limit, condition);
    if (!form) {
      reason = "A has no real modal form of condition <= " + std::to_string(options.modal_condition_limit);
      continue;
    }
    const Eigen::VectorXd theta = eigenvalue_parameters(form->blocks);
    if (!stable(form->blocks, theta)) throw std::invalid_argument("refine_poles: need a stable A (spectral radius < 1)");
    auto problem = std::make_unique<RefinementProblem>(data, form->blocks, c * form->T, theta, options.max_samples);
    if (!problem->valid()) {
      reason = "the B/D/x0 regression or the simulation broke down at the start";
      continue;
    }
    const double fit = problem->fit();
    auto solver = std::make_unique<LevenbergMarquardt>(*problem, lm);
    runs.push_back(Run{k, std::move(*form), std::move(problem), std::move(solver), fit});
  }
  PoleRefinementResult result;
  if (runs.empty()) {
    result.A = starts.front().A;
    result.C = starts.front().C;
    result.termination = "not refined: " + reason;
    return result;
  }
  // The race: every start a few iterations, then the lowest cost alone.
  if (runs.size() > 1)
    for (Run& r : runs) r.solver->iterate_up_to(options.race_iterations);
  Run& best = *std::min_element(runs.begin(), runs.end(), [](const Run& x, const Run& y) {
    return x.solver->current_cost() < y.solver->current_cost();
  });
  best.solver->iterate_up_to(options.max_iterations);
  const LevenbergMarquardt::Summary summary = best.solver->finish();
  result.start = best.start;
  result.C = starts[best.start].C;
  result.iterations = summary.iterations;
  result.termination = summary.termination;
  result.initial_fit = best.initial_fit;
  result.final_fit = best.problem->fit();
  result.refined = summary.final_cost < summary.initial_cost;
  if (result.refined) {
    // A = T A_m T^-1, as A^T = T^-T (T A_m)^T: a solve, not an inverse.
    const Eigen::MatrixXd t_am =
        best.form.T * modal_matrix(best.form.blocks, best.problem->parameters(), starts[best.start].A.rows());
    result.A = best.form.T.transpose().partialPivLu().solve(t_am.transpose()).transpose();
  } else {
    result.A = starts[best.start].A;
    result.final_fit = result.initial_fit;
  }
  return result;
}

}  // namespace sysid
