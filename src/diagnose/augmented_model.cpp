// Simulation of a nominal model augmented with physics blocks; the equations are
// documented in include/sysid/diagnose/augmented_model.hpp, each kind's own in
// src/diagnose/kinds/.
#include "sysid/diagnose/augmented_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "sysid/core/discretize.hpp"
#include "sysid/core/errors.hpp"
#include "sysid/core/flush_subnormals.hpp"
#include "sysid/core/math_constants.hpp"
#include "sysid/core/simulate.hpp"
#include "sysid/diagnose/physics_kind.hpp"

namespace sysid {

const char* quantity_name(OutputQuantity q) {
  switch (q) {
    case OutputQuantity::position: return "position";
    case OutputQuantity::velocity: return "velocity";
    case OutputQuantity::acceleration: return "acceleration";
    case OutputQuantity::other: return "other";
    case OutputQuantity::unknown: break;
  }
  return "unknown";
}

OutputQuantity parse_output_quantity(const std::string& name) {
  for (OutputQuantity q : {OutputQuantity::position, OutputQuantity::velocity, OutputQuantity::acceleration, OutputQuantity::other})
    if (name == quantity_name(q)) return q;
  throw std::invalid_argument("unknown output quantity '" + name + "' (expected position, velocity, acceleration or other)");
}

std::vector<OutputQuantity> parse_output_quantities(const std::vector<std::string>& names, Eigen::Index outputs) {
  if (names.size() != 1 && static_cast<Eigen::Index>(names.size()) != outputs)
    throw std::invalid_argument("give one output quantity for every output or one per output (" + std::to_string(outputs) +
                                " outputs, " + std::to_string(names.size()) + " given)");
  std::vector<OutputQuantity> out;
  for (Eigen::Index i = 0; i < outputs; ++i) out.push_back(parse_output_quantity(names[names.size() == 1 ? 0 : static_cast<std::size_t>(i)]));
  return out;
}

namespace {

/// A parallel mode in modal form, exactly discretised at step h: q'' + 2 zeta w q' + w^2 q = f.
struct ModeState {
  long input = 0, output = 0;
  double omega = 0.0, zeta = 0.0, static_gain = 0.0, velocity_gain = 0.0;
  Eigen::Matrix2d Phi;
  Eigen::Vector2d Gamma;
  Eigen::Vector2d z = Eigen::Vector2d::Zero();  ///< (q, q')

  double output_value() const { return static_gain * omega * omega * z[0] + velocity_gain * omega * z[1]; }
  double output_rate(double f) const {
    const double acceleration = f - 2.0 * zeta * omega * z[1] - omega * omega * z[0];
    return static_gain * omega * omega * z[1] + velocity_gain * omega * acceleration;
  }
};

ModeState make_mode(const ParallelMode& p, double h) {
  ModeState m;
  m.input = p.input;
  m.output = p.output;
  m.omega = kTwoPi * p.freq_hz;
  m.zeta = p.damping;
  m.static_gain = p.static_gain;
  m.velocity_gain = p.velocity_gain;
  StateSpace c(Eigen::Matrix2d{{0.0, 1.0}, {-m.omega * m.omega, -2.0 * m.zeta * m.omega}}, Eigen::Vector2d(0.0, 1.0),
               Eigen::RowVector2d(1.0, 0.0), Eigen::MatrixXd::Zero(1, 1), 0.0);
  const StateSpace d = c2d_zoh(c, h);
  m.Phi = d.A;
  m.Gamma = d.B;
  return m;
}

struct LagState {
  long input = 0;
  double decay = 0.0, mean_factor = 0.0;  ///< a = exp(-w h); mean of (l - w) over the step is (l0 - w)(1 - a)/(w h)
  double state = 0.0;
};

bool needs_core_loop(const std::vector<PhysicsBlock>& blocks) {
  return std::any_of(blocks.begin(), blocks.end(), [](const PhysicsBlock& b) {
    const PhysicsKind& k = physics_kind(b.kind);
    const BlockStage s = k.info().stage;
    return s == BlockStage::plant_feedback || s == BlockStage::plant_parallel || k.lag_corner_hz(b) > 0.0;
  });
}

/// The blocks of a stage, in the kinds' chain order (stable: equal kinds keep the file's order).
std::vector<const PhysicsBlock*> in_chain_order(const std::vector<PhysicsBlock>& blocks, std::initializer_list<BlockStage> stages) {
  std::vector<const PhysicsBlock*> out;
  for (const auto& b : blocks)
    if (std::find(stages.begin(), stages.end(), b.info().stage) != stages.end()) out.push_back(&b);
  std::stable_sort(out.begin(), out.end(),
                   [](const PhysicsBlock* a, const PhysicsBlock* b) { return a->info().chain_order < b->info().chain_order; });
  return out;
}

}  // namespace

void check_physics_blocks(const std::vector<PhysicsBlock>& blocks, Eigen::Index m, Eigen::Index l, double Ts) {
  for (const auto& b : blocks) {
    const PhysicsKind& kind = physics_kind(b.kind);  // unknown kind -> invalid_argument
    if (b.input < 0 || b.input >= m)
      throw std::invalid_argument(b.kind + ": input channel " + std::to_string(b.input) + " out of range (model has " +
                                  std::to_string(m) + " inputs)");
    if (b.output < 0 || b.output >= l)
      throw std::invalid_argument(b.kind + ": output channel " + std::to_string(b.output) + " out of range (model has " +
                                  std::to_string(l) + " outputs)");
    for (const char* name : kind.info().parameters)
      if (!std::isfinite(b.param(name))) throw std::invalid_argument(b.kind + ": parameter " + name + " is not finite");
    kind.check(b, m, l, Ts);
  }
}

Eigen::MatrixXd actuator_output(const std::vector<PhysicsBlock>& blocks, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                double Ts, Eigen::Index samples) {
  Eigen::MatrixXd w = u.topRows(samples);
  if (samples == 0) return w;
  for (const PhysicsBlock* b : in_chain_order(blocks, {BlockStage::actuator})) physics_kind(b->kind).actuate(*b, Ts, w.col(b->input));
  return w;
}

AugmentedSimulator::AugmentedSimulator(const StateSpace& nominal, int substeps, Eigen::VectorXd x0,
                                       std::vector<OutputQuantity> output_quantities)
    : m_nominal(nominal), m_substeps(substeps), m_x0(std::move(x0)), m_quantities(std::move(output_quantities)) {
  nominal.validate();
  if (!nominal.is_discrete()) throw std::invalid_argument("AugmentedSimulator: need a discrete nominal model (Ts > 0)");
  if (substeps < 1) throw std::invalid_argument("AugmentedSimulator: need substeps >= 1");
  if (m_x0.size() != 0 && m_x0.size() != nominal.order())
    throw std::invalid_argument("AugmentedSimulator: need x0.size() == order or 0");
  if (!m_quantities.empty() && static_cast<Eigen::Index>(m_quantities.size()) != nominal.outputs())
    throw std::invalid_argument("AugmentedSimulator: need one output quantity per output (" +
                                std::to_string(m_quantities.size()) + " for " + std::to_string(nominal.outputs()) + ")");
  try {
    m_continuous = d2c_zoh(nominal);
  } catch (const NumericalError& e) {
    m_warnings.push_back(std::string("the nominal model has no continuous-time equivalent (") + e.what() +
                         "): plant forces use one step per sample and a backward-difference velocity");
    m_substeps = 1;
  }
  const double h = nominal.Ts / m_substeps;
  m_step = m_substeps == 1 ? nominal : c2d_zoh(*m_continuous, h);

  // Integrator states of the velocity and acceleration outputs (p' = y, or v' = a
  // and p' = v), appended to the continuous equivalent and discretised with it.
  const Eigen::Index n = nominal.order(), m = nominal.inputs(), l = nominal.outputs();
  m_position_state.assign(static_cast<std::size_t>(l), -1);
  m_velocity_state.assign(static_cast<std::size_t>(l), -1);
  Eigen::Index extra = 0;
  for (Eigen::Index i = 0; i < l; ++i) {
    const OutputQuantity q = output_quantity(i);
    if (q == OutputQuantity::acceleration) m_velocity_state[i] = n + extra++;
    if (q == OutputQuantity::velocity || q == OutputQuantity::acceleration) m_position_state[i] = n + extra++;
  }
  if (extra == 0 || !m_continuous) return;
  const StateSpace& c = *m_continuous;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n + extra, n + extra), B = Eigen::MatrixXd::Zero(n + extra, m);
  A.topLeftCorner(n, n) = c.A;
  B.topRows(n) = c.B;
  for (Eigen::Index i = 0; i < l; ++i) {
    const Eigen::Index first = m_velocity_state[i] >= 0 ? m_velocity_state[i] : m_position_state[i];
    if (first < 0) continue;
    A.row(first).head(n) = c.C.row(i);
    B.row(first) = c.D.row(i);
    if (m_velocity_state[i] >= 0) A(m_position_state[i], m_velocity_state[i]) = 1.0;
  }
  m_step_integrated = c2d_zoh(StateSpace(A, B, Eigen::MatrixXd::Zero(l, n + extra), Eigen::MatrixXd::Zero(l, m), 0.0), h);
}

OutputQuantity AugmentedSimulator::output_quantity(Eigen::Index i) const {
  return m_quantities.empty() ? OutputQuantity::unknown : m_quantities[static_cast<std::size_t>(i)];
}

Eigen::MatrixXd AugmentedSimulator::simulate(const std::vector<PhysicsBlock>& blocks,
                                             const Eigen::Ref<const Eigen::MatrixXd>& u, Eigen::Index samples) const {
  const StateSpace& nom = m_nominal;
  const Eigen::Index m = nom.inputs(), l = nom.outputs(), n = nom.order();
  if (u.cols() != m)
    throw std::invalid_argument("simulate augmented: need u.cols() == nominal inputs (" + std::to_string(u.cols()) +
                                " != " + std::to_string(m) + ")");
  const Eigen::Index N = samples < 0 ? u.rows() : std::min<Eigen::Index>(samples, u.rows());
  const double Ts = nom.Ts;
  check_physics_blocks(blocks, m, l, Ts);

  const Eigen::MatrixXd drive = actuator_output(blocks, u, Ts, N);
  Eigen::MatrixXd y(N, l);

  if (!needs_core_loop(blocks)) {
    y = sysid::simulate(nom, drive, m_x0);
  } else {
    const int M = m_substeps;
    const double h = Ts / M;
    std::vector<ModeState> modes;
    std::vector<LagState> lags;
    std::vector<PlantForce> forces;
    for (const auto& b : blocks) {
      const PhysicsKind& kind = physics_kind(b.kind);
      for (const ParallelMode& p : kind.parallel_modes(b)) modes.push_back(make_mode(p, h));
      if (const double corner = kind.lag_corner_hz(b); corner > 0.0) {
        const double w = kTwoPi * corner;
        const double a = std::exp(-w * h);
        lags.push_back({b.input, a, (1.0 - a) / (w * h), 0.0});
      }
      PlantForce force;
      if (kind.plant_force(b, force)) forces.push_back(force);
    }
    // The reading of each output the forces act from.
    std::vector<OutputQuantity> reading(static_cast<std::size_t>(l));
    for (Eigen::Index i = 0; i < l; ++i) {
      const OutputQuantity q = output_quantity(i);
      reading[static_cast<std::size_t>(i)] = q == OutputQuantity::velocity || q == OutputQuantity::acceleration ? q : OutputQuantity::position;
    }
    const bool integrated = m_step_integrated.order() > 0;
    const bool any_integral = std::any_of(m_position_state.begin(), m_position_state.end(), [](Eigen::Index s) { return s >= 0; });
    const StateSpace& step = integrated ? m_step_integrated : m_step;
    const Eigen::Index states = step.order();
    // Buffers allocated once: this loop runs N * substeps times per simulation
    // and a fit runs hundreds of simulations.
    Eigen::VectorXd x = Eigen::VectorXd::Zero(states);
    if (m_x0.size()) x.head(n) = m_x0;
    Eigen::VectorXd x_next(states), x_rate(n), f(m), drive_force(m), f_previous = Eigen::VectorXd::Zero(m),
        structural(l), direct(l), updated(l), position(l), velocity(l), previous_position(l), y_k(l), mode_out(l),
        running_velocity = Eigen::VectorXd::Zero(l), running_position = Eigen::VectorXd::Zero(l),
        mode_integral = Eigen::VectorXd::Zero(l), mode_double_integral = Eigen::VectorXd::Zero(l);
    const bool exact_velocity = m_continuous.has_value();
    // With a direct feedthrough D the reading that is the output itself (a
    // position or a velocity) depends on the force it causes: r = C x + D f(r) is
    // solved by fixed-point iteration (it contracts while |D df/dr| < 1, i.e. for
    // any force small against the drive).
    const bool feedthrough = nom.D.cwiseAbs().maxCoeff() > 0.0;
    const int feedthrough_iterations = feedthrough ? 20 : 1;
    bool first = true;
    // The plant's and the modes' states decay where the drive is zero (core/flush_subnormals.hpp).
    const ScopedFlushSubnormals flush;
    for (Eigen::Index k = 0; k < N; ++k) {
      for (int s = 0; s < M; ++s) {
        // The force the plant receives over this step: the (lagged) drive plus
        // the plant's own forces evaluated at the step's start.
        f = drive.row(k).transpose();
        for (const auto& lag : lags) f[lag.input] = f[lag.input] + (lag.state - f[lag.input]) * lag.mean_factor;
        mode_out.setZero();
        for (const auto& mode : modes) mode_out[mode.output] += mode.output_value();
        if (!forces.empty()) {
          const auto xn = x.head(n);
          structural.noalias() = nom.C * xn;
          structural += mode_out;
          // The reading's derivative of the structural output (position outputs).
          if (exact_velocity) {
            x_rate.noalias() = m_continuous->A * xn;
            x_rate.noalias() += m_continuous->B * f_previous;
            velocity.noalias() = nom.C * x_rate;
            for (const auto& mode : modes) velocity[mode.output] += mode.output_rate(f_previous[mode.input]);
          } else {
            if (first) velocity.setZero();
            else velocity = (structural - previous_position) / h;
            previous_position = structural;
          }
          for (Eigen::Index i = 0; i < l; ++i) {
            const OutputQuantity q = reading[static_cast<std::size_t>(i)];
            if (q == OutputQuantity::position) {
              position[i] = structural[i];
            } else {
              const double p = integrated ? x[m_position_state[i]] : running_position[i];
              if (q == OutputQuantity::velocity) {
                position[i] = p + mode_integral[i];
                velocity[i] = structural[i];
              } else {
                const double v = integrated ? x[m_velocity_state[i]] : running_velocity[i];
                position[i] = p + mode_double_integral[i];
                velocity[i] = v + mode_integral[i];
              }
            }
          }
          drive_force = f;
          direct = structural;
          for (int iteration = 0; iteration < feedthrough_iterations; ++iteration) {
            f = drive_force;
            for (const auto& force : forces) f[force.input] += force(position[force.output], velocity[force.output]);
            if (!feedthrough) break;
            updated = structural;
            updated.noalias() += nom.D * f;
            double change = 0.0;
            for (Eigen::Index i = 0; i < l; ++i) {
              const OutputQuantity q = reading[static_cast<std::size_t>(i)];
              if (q == OutputQuantity::acceleration) continue;  // D f drives the integrators, not the reading
              double& r = q == OutputQuantity::position ? position[i] : velocity[i];
              change = std::max(change, std::abs(updated[i] - direct[i]));
              r = updated[i];
            }
            direct.swap(updated);
            if (change <= 1e-13 * (1.0 + direct.cwiseAbs().maxCoeff())) break;
          }
        }
        if (s == 0) {
          y_k.noalias() = nom.C * x.head(n);
          y_k.noalias() += nom.D * f;
          y_k += mode_out;
          y.row(k) = y_k.transpose();
        }
        // Running sums: the integrals themselves without a continuous
        // equivalent, and the modal terms' share of them (rectangle rule).
        if (any_integral && !integrated) {
          y_k.noalias() = nom.C * x.head(n);
          y_k.noalias() += nom.D * f;
          for (Eigen::Index i = 0; i < l; ++i) {
            const OutputQuantity q = reading[static_cast<std::size_t>(i)];
            if (q == OutputQuantity::velocity) running_position[i] += h * y_k[i];
            if (q == OutputQuantity::acceleration) {
              running_position[i] += h * running_velocity[i];
              running_velocity[i] += h * y_k[i];
            }
          }
        }
        if (any_integral && !modes.empty()) {
          mode_double_integral += h * mode_integral;
          mode_integral += h * mode_out;
        }
        x_next.noalias() = step.A * x;
        x_next.noalias() += step.B * f;
        x.swap(x_next);
        for (auto& mode : modes) mode.z = mode.Phi * mode.z + mode.Gamma * f[mode.input];
        for (auto& lag : lags) lag.state = lag.decay * lag.state + (1.0 - lag.decay) * drive(k, lag.input);
        f_previous = f;
        first = false;
      }
    }
  }

  // Sensor stage, in the nominal's output coordinates.
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(N, 0.0, static_cast<double>(N - 1) * Ts);
  const SensorInputs sensor{nom, drive, t};
  for (const PhysicsBlock* b : in_chain_order(blocks, {BlockStage::sensor, BlockStage::coupling}))
    physics_kind(b->kind).sense(*b, sensor, y);
  return y;
}

Eigen::MatrixXd simulate_augmented(const AugmentedModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u) {
  const AugmentedSimulator simulator(model.nominal, model.substeps, model.x0, model.output_quantities);
  Eigen::MatrixXd u_dev = u;
  if (model.input_offset.size() != 0) u_dev.rowwise() -= model.input_offset.transpose();
  Eigen::MatrixXd y = simulator.simulate(model.blocks, u_dev);
  if (model.output_offset.size() != 0) y.rowwise() += model.output_offset.transpose();
  return y;
}

}  // namespace sysid
