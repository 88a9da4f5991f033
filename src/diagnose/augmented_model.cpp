// Simulation of a nominal model augmented with physics blocks; the equations are
// documented in include/sysid/diagnose/augmented_model.hpp.
#include "sysid/diagnose/augmented_model.hpp"
#include "sysid/core/math_constants.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "sysid/core/discretize.hpp"
#include "sysid/core/errors.hpp"
#include "sysid/core/simulate.hpp"

namespace sysid {

namespace {


bool is_kind(const PhysicsBlock& b, const char* kind) { return b.kind == kind; }

void require(bool ok, const PhysicsBlock& b, const char* parameter, const char* condition) {
  if (!ok) throw std::invalid_argument(b.kind + ": need " + parameter + " " + condition);
}

/// Bounds and finiteness of each kind's parameters (the simulation would
/// otherwise produce NaN or a non-causal delay).
void check_parameters(const PhysicsBlock& b, double Ts) {
  for (const char* name : b.info().parameters) {
    const double v = b.param(name);
    if (!std::isfinite(v)) throw std::invalid_argument(b.kind + ": parameter " + name + " is not finite");
  }
  if (is_kind(b, "missing_mode") || is_kind(b, "mode_shift")) {
    require(b.param("freq_hz") > 0.0 && b.param("freq_hz") < 0.5 / Ts, b, "freq_hz", "in (0, Nyquist)");
    require(b.param("damping") > 0.0, b, "damping", "> 0");
    if (is_kind(b, "mode_shift")) {
      require(b.param("nominal_freq_hz") > 0.0 && b.param("nominal_freq_hz") < 0.5 / Ts, b, "nominal_freq_hz",
              "in (0, Nyquist)");
      require(b.param("nominal_damping") > 0.0, b, "nominal_damping", "> 0");
    }
  } else if (is_kind(b, "time_delay")) {
    require(b.param("delay_s") >= 0.0, b, "delay_s", ">= 0");
  } else if (is_kind(b, "input_lag")) {
    require(b.param("corner_hz") > 0.0, b, "corner_hz", "> 0");
  } else if (is_kind(b, "coulomb_friction")) {
    require(b.param("velocity_scale") > 0.0, b, "velocity_scale", "> 0");
  } else if (is_kind(b, "backlash") || is_kind(b, "deadzone")) {
    require(b.param("width") >= 0.0, b, "width", ">= 0");
  } else if (is_kind(b, "saturation")) {
    require(b.param("limit") > 0.0 || b.param("storage_pole") > 0.0, b, "limit", "> 0 (an amplifier's +-limit)");
    require(b.param("storage_pole") >= 0.0 && b.param("storage_pole") < 1.0, b, "storage_pole", "in [0, 1)");
    require(b.param("spill") >= 0.0 && b.param("spill") <= 1.0, b, "spill", "in [0, 1]");
  } else if (is_kind(b, "periodic_disturbance")) {
    require(b.param("freq_hz") > 0.0, b, "freq_hz", "> 0");
  }
}

// ---- actuator stage ---------------------------------------------------------

/// An amplifier clipping at +-limit (storage_pole a = 0), or the overflow of a
/// first-order store the input fills (a tank; 0 < a < 1). The store's level, in
/// input units (unit DC gain),
///   v[k+1] = min(a v[k] + (1 - a) w[k], limit),
/// and what flows on to the plant is the level the next stage sees,
///   z[k+1] = v[k+1] + spill * overflow[k] / (1 - a),
/// overflow = the part of a v + (1 - a) w above the limit, of which the fraction
/// `spill` reaches the next stage at once (1 / (1 - a) turns an overflowing
/// volume into the level that would carry it out in one step; the rest is lost).
/// The nominal holds the store's own dynamics (its pole a, e.g. the upper tank
/// of cascaded tanks), so the block hands it the input that makes that pole
/// reproduce z exactly: w_out[k] = (z[k+1] - a z[k]) / (1 - a), causal because
/// z[k+1] depends on w[k] only; below the limit w_out = w. Physics: the overflow
/// of the upper tank in M. Schoukens, P. Mattsson, T. Wigren and J.P. Noel,
/// "Cascaded tanks benchmark combining soft and hard nonlinearities", 2016 (part
/// of the spill falls into the lower tank). The store starts filled to its first
/// input; it never runs dry (no lower limit).
void apply_saturation(double limit, double a, double spill, Eigen::Ref<Eigen::VectorXd> w) {
  if (a == 0.0) {
    w = w.cwiseMax(-limit).cwiseMin(limit);
    return;
  }
  if (w.size() == 0) return;
  double level = std::min(w[0], limit), seen = level;
  for (Eigen::Index k = 0; k < w.size(); ++k) {
    const double filled = a * level + (1.0 - a) * w[k];
    const double next_level = std::min(filled, limit);
    const double next_seen = next_level + spill * (filled - next_level) / (1.0 - a);
    w[k] = (next_seen - a * seen) / (1.0 - a);
    level = next_level;
    seen = next_seen;
  }
}

void apply_deadzone(double width, Eigen::Ref<Eigen::VectorXd> w) {
  const double half = 0.5 * width;
  for (Eigen::Index k = 0; k < w.size(); ++k) {
    const double v = w[k];
    w[k] = v > half ? v - half : (v < -half ? v + half : 0.0);
  }
}

/// Play operator: the output follows the input at a distance of half the width
/// and holds while the input moves inside the play.
void apply_backlash(double width, Eigen::Ref<Eigen::VectorXd> w) {
  const double half = 0.5 * width;
  double b = std::clamp(0.0, w[0] - half, w[0] + half);
  for (Eigen::Index k = 0; k < w.size(); ++k) {
    b = std::clamp(b, w[k] - half, w[k] + half);
    w[k] = b;
  }
}

void apply_hysteresis(double alpha, double beta, double gamma, Eigen::Ref<Eigen::VectorXd> w) {
  double h = 0.0, previous = w[0];
  for (Eigen::Index k = 1; k < w.size(); ++k) {
    const double du = w[k] - previous;
    previous = w[k];
    h += alpha * du - beta * std::abs(du) * h - gamma * du * std::abs(h);
    w[k] -= h;
  }
}

/// w[k - d] with d = delay / Ts possibly fractional (linear interpolation) and
/// zero (rest) before the first sample.
void apply_delay(double delay_samples, Eigen::Ref<Eigen::VectorXd> w) {
  if (!std::isfinite(delay_samples)) throw std::invalid_argument("time_delay: the delay is not a finite number");
  const Eigen::VectorXd original = w;
  // A delay beyond the record (either way) leaves nothing of it; clamping first
  // keeps the conversion to an index defined (a file may say delay_s 1e300).
  const double span = static_cast<double>(w.size()) + 1.0;
  const double clamped = std::clamp(delay_samples, -span, span);
  const auto whole = static_cast<Eigen::Index>(std::floor(clamped));
  const double frac = clamped - static_cast<double>(whole);
  auto at = [&](Eigen::Index k) { return k >= 0 && k < original.size() ? original[k] : 0.0; };
  for (Eigen::Index k = 0; k < w.size(); ++k) w[k] = (1.0 - frac) * at(k - whole) + frac * at(k - whole - 1);
}

// ---- linear core ------------------------------------------------------------

/// A mode in modal form, exactly discretised at step h: q'' + 2 zeta w q' + w^2 q = f.
struct ModeState {
  long input = 0, output = 0;
  double omega = 0.0, zeta = 0.0, static_gain = 0.0, velocity_gain = 0.0;
  Eigen::Matrix2d Phi;
  Eigen::Vector2d Gamma;
  Eigen::Vector2d z = Eigen::Vector2d::Zero();  ///< (q, q')

  double position() const { return static_gain * omega * omega * z[0] + velocity_gain * omega * z[1]; }
  double velocity(double f) const {
    const double acceleration = f - 2.0 * zeta * omega * z[1] - omega * omega * z[0];
    return static_gain * omega * omega * z[1] + velocity_gain * omega * acceleration;
  }
};

/// A parallel mode (static_gain w^2 + velocity_gain w s) / (s^2 + 2 zeta w s + w^2).
ModeState make_mode(long input, long output, double freq_hz, double zeta, double static_gain, double velocity_gain,
                    double h) {
  ModeState m;
  m.input = input;
  m.output = output;
  m.omega = kTwoPi * freq_hz;
  m.zeta = zeta;
  m.static_gain = static_gain;
  m.velocity_gain = velocity_gain;
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

struct FeedbackForce {
  long input = 0, output = 0;
  bool friction = false;
  double level = 0.0, velocity_scale = 1.0;  ///< friction
  double coefficient = 0.0, linear = 0.0;    ///< cubic stiffness: coefficient y^3 + linear y
};

bool needs_core_loop(const std::vector<PhysicsBlock>& blocks) {
  return std::any_of(blocks.begin(), blocks.end(), [](const PhysicsBlock& b) {
    const BlockStage s = b.info().stage;
    return s == BlockStage::plant_feedback || s == BlockStage::plant_parallel || is_kind(b, "input_lag");
  });
}

}  // namespace

void check_physics_blocks(const std::vector<PhysicsBlock>& blocks, Eigen::Index m, Eigen::Index l, double Ts) {
  for (const auto& b : blocks) {
    (void)b.info();  // unknown kind -> invalid_argument
    if (b.input < 0 || b.input >= m)
      throw std::invalid_argument(b.kind + ": input channel " + std::to_string(b.input) + " out of range (model has " +
                                  std::to_string(m) + " inputs)");
    if (b.output < 0 || b.output >= l)
      throw std::invalid_argument(b.kind + ": output channel " + std::to_string(b.output) + " out of range (model has " +
                                  std::to_string(l) + " outputs)");
    if (is_kind(b, "cross_coupling") && b.input >= l)
      throw std::invalid_argument("cross_coupling: the source input " + std::to_string(b.input) +
                                  " has no direct output to copy (model has " + std::to_string(l) + " outputs)");
    check_parameters(b, Ts);
  }
}

Eigen::MatrixXd actuator_output(const std::vector<PhysicsBlock>& blocks, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                double Ts, Eigen::Index samples) {
  Eigen::MatrixXd w = u.topRows(samples);
  if (samples == 0) return w;
  // Amplifier first, then the transport delay, then the mechanical play and the
  // actuator material; each block acts on its own input channel.
  for (const char* kind : {"saturation", "time_delay", "deadzone", "backlash", "hysteresis"}) {
    for (const auto& b : blocks) {
      if (b.kind != kind) continue;
      auto col = w.col(b.input);
      if (b.kind == "saturation")
        apply_saturation(b.param("limit"), b.param("storage_pole"), b.param("spill"), col);
      else if (b.kind == "time_delay") apply_delay(b.param("delay_s") / Ts, col);
      else if (b.kind == "deadzone") apply_deadzone(b.param("width"), col);
      else if (b.kind == "backlash") apply_backlash(b.param("width"), col);
      else apply_hysteresis(b.param("alpha"), b.param("beta"), b.param("gamma"), col);
    }
  }
  return w;
}

AugmentedSimulator::AugmentedSimulator(const StateSpace& nominal, int substeps, Eigen::VectorXd x0)
    : m_nominal(nominal), m_substeps(substeps), m_x0(std::move(x0)) {
  nominal.validate();
  if (!nominal.is_discrete()) throw std::invalid_argument("AugmentedSimulator: need a discrete nominal model (Ts > 0)");
  if (substeps < 1) throw std::invalid_argument("AugmentedSimulator: need substeps >= 1");
  if (m_x0.size() != 0 && m_x0.size() != nominal.order())
    throw std::invalid_argument("AugmentedSimulator: need x0.size() == order or 0");
  try {
    m_continuous = d2c_zoh(nominal);
  } catch (const NumericalError& e) {
    m_warnings.push_back(std::string("the nominal model has no continuous-time equivalent (") + e.what() +
                         "): plant forces use one step per sample and a backward-difference velocity");
    m_substeps = 1;
  }
  m_step = m_substeps == 1 ? nominal : c2d_zoh(*m_continuous, nominal.Ts / m_substeps);
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
    std::vector<FeedbackForce> feedback;
    for (const auto& b : blocks) {
      if (is_kind(b, "missing_mode"))
        modes.push_back(make_mode(b.input, b.output, b.param("freq_hz"), b.param("damping"), b.param("static_gain"),
                                  b.param("velocity_gain"), h));
      if (is_kind(b, "mode_shift")) {
        // The nominal mode (numerator b1 s + b0) out, the same numerator over the
        // moved denominator in: static_gain = b0 / w^2, velocity_gain = b1 / w.
        const double b0 = b.param("numerator_b0"), b1 = b.param("numerator_b1");
        const double w_old = kTwoPi * b.param("nominal_freq_hz"), w_new = kTwoPi * b.param("freq_hz");
        modes.push_back(make_mode(b.input, b.output, b.param("nominal_freq_hz"), b.param("nominal_damping"),
                                  -b0 / (w_old * w_old), -b1 / w_old, h));
        modes.push_back(make_mode(b.input, b.output, b.param("freq_hz"), b.param("damping"), b0 / (w_new * w_new),
                                  b1 / w_new, h));
      }
      if (is_kind(b, "input_lag")) {
        const double w = kTwoPi * b.param("corner_hz");
        const double a = std::exp(-w * h);
        lags.push_back({b.input, a, (1.0 - a) / (w * h), 0.0});
      }
      if (is_kind(b, "coulomb_friction"))
        feedback.push_back({b.input, b.output, true, b.param("level"), b.param("velocity_scale"), 0.0});
      if (is_kind(b, "cubic_stiffness"))
        feedback.push_back({b.input, b.output, false, 0.0, 1.0, b.param("coefficient"), b.param("linear_coefficient")});
    }
    // Buffers allocated once: this loop runs N * substeps times per simulation
    // and a fit runs hundreds of simulations.
    Eigen::VectorXd x = m_x0.size() ? m_x0 : Eigen::VectorXd::Zero(n);
    Eigen::VectorXd x_next(n), x_rate(n), f(m), drive_force(m), f_previous = Eigen::VectorXd::Zero(m), position(l),
        structural_position(l), updated_position(l), velocity(l), previous_position(l), y_k(l);
    const bool exact_velocity = m_continuous.has_value();
    // With a direct feedthrough D the measured position depends on the force it
    // causes: p = C x + D f(p) is solved by fixed-point iteration (it contracts
    // while |D df/dp| < 1, i.e. for any force small against the drive).
    const bool feedthrough = nom.D.cwiseAbs().maxCoeff() > 0.0;
    const int feedthrough_iterations = feedthrough ? 20 : 1;
    bool first = true;
    for (Eigen::Index k = 0; k < N; ++k) {
      for (int s = 0; s < M; ++s) {
        // The force the plant receives over this step: the (lagged) drive minus
        // the plant's own nonlinear forces evaluated at the step's start.
        f = drive.row(k).transpose();
        for (const auto& lag : lags) f[lag.input] = f[lag.input] + (lag.state - f[lag.input]) * lag.mean_factor;
        if (!feedback.empty()) {
          position.noalias() = nom.C * x;
          for (const auto& mode : modes) position[mode.output] += mode.position();
          if (exact_velocity) {
            x_rate.noalias() = m_continuous->A * x;
            x_rate.noalias() += m_continuous->B * f_previous;
            velocity.noalias() = nom.C * x_rate;
            for (const auto& mode : modes) velocity[mode.output] += mode.velocity(f_previous[mode.input]);
          } else {
            if (first) velocity.setZero();
            else velocity = (position - previous_position) / h;
            previous_position = position;
          }
          drive_force = f;
          structural_position = position;
          for (int iteration = 0; iteration < feedthrough_iterations; ++iteration) {
            f = drive_force;
            for (const auto& fb : feedback) {
              const double p = position[fb.output], v = velocity[fb.output];
              f[fb.input] -= fb.friction ? fb.level * std::tanh(v / fb.velocity_scale) : (fb.coefficient * p * p + fb.linear) * p;
            }
            if (!feedthrough) break;
            updated_position = structural_position;
            updated_position.noalias() += nom.D * f;
            const double change = (updated_position - position).cwiseAbs().maxCoeff();
            position.swap(updated_position);
            if (change <= 1e-13 * (1.0 + position.cwiseAbs().maxCoeff())) break;
          }
        }
        if (s == 0) {
          y_k.noalias() = nom.C * x;
          y_k.noalias() += nom.D * f;
          for (const auto& mode : modes) y_k[mode.output] += mode.position();
          y.row(k) = y_k.transpose();
        }
        x_next.noalias() = m_step.A * x;
        x_next.noalias() += m_step.B * f;
        x.swap(x_next);
        for (auto& mode : modes) mode.z = mode.Phi * mode.z + mode.Gamma * f[mode.input];
        for (auto& lag : lags) lag.state = lag.decay * lag.state + (1.0 - lag.decay) * drive(k, lag.input);
        f_previous = f;
        first = false;
      }
    }
  }

  // Sensor stage, in the nominal's output coordinates.
  for (const auto& b : blocks)
    if (is_kind(b, "gain_error")) y.col(b.output) *= b.param("ratio");
  for (const auto& b : blocks) {
    if (!is_kind(b, "cross_coupling")) continue;
    // The nominal's direct path of the source input, scaled: the coupling adds
    // the motion input j causes at output j, seen at output i.
    StateSpace direct(nom.A, nom.B.col(b.input), nom.C.row(b.input), nom.D.block(b.input, b.input, 1, 1), Ts);
    y.col(b.output) += b.param("gain") * sysid::simulate(direct, drive.col(b.input)).col(0);
  }
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(N, 0.0, static_cast<double>(N - 1) * Ts);
  for (const auto& b : blocks) {
    if (is_kind(b, "offset_drift"))
      y.col(b.output).array() += b.param("offset") + b.param("slope") * t.array();
    if (is_kind(b, "periodic_disturbance"))
      y.col(b.output).array() +=
          b.param("amplitude") * (kTwoPi * b.param("freq_hz") * t.array() + b.param("phase_rad")).sin();
  }
  return y;
}

Eigen::MatrixXd simulate_augmented(const AugmentedModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u) {
  const AugmentedSimulator simulator(model.nominal, model.substeps, model.x0);
  Eigen::MatrixXd u_dev = u;
  if (model.input_offset.size() != 0) u_dev.rowwise() -= model.input_offset.transpose();
  Eigen::MatrixXd y = simulator.simulate(model.blocks, u_dev);
  if (model.output_offset.size() != 0) y.rowwise() += model.output_offset.transpose();
  return y;
}

}  // namespace sysid
