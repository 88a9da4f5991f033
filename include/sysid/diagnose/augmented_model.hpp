#pragma once
/// @file
/// Purpose: a nominal discrete state-space model augmented with physics blocks
/// (physics_block.hpp), and its simulation. This is what `sysid diagnose` writes
/// as `"type": "augmented"` and what `sysid simulate` runs.
///
/// Method (per sample k, input held over the sample as the nominal's ZOH assumes):
///  1. actuator: u_j -> the actuator blocks in chain order (saturation,
///     time_delay, deadzone, backlash, hysteresis: each kind's `actuate`);
///  2. linear core, stepped `substeps` times per sample at h = Ts/substeps:
///     the nominal (x+ = Phi x + Gamma f), an input lag per channel (first order,
///     its exact mean over the step is the force held), the parallel modal terms
///     (missing and moved modes: s^2 + 2 zeta w s + w^2, output static_gain w^2 q
///     + velocity_gain w q', exactly ZOH-discretised); the plant force
///     f_j = drive_j + sum of the plant's own forces at j (friction, springs,
///     constant forces: each kind's `plant_force`), evaluated at the start of
///     each step from the motion at the collocated output i. That motion is read
///     as output i's quantity says: a position output gives the position y_i =
///     C x + modes and the velocity exactly, C (A_c x + B_c f), when the nominal
///     has a continuous equivalent (otherwise a backward difference); a velocity
///     output gives the velocity y_i and the position as its exact integral (an
///     integrator state appended to the continuous equivalent, p' = C_i x +
///     D_i f, discretised with it); an acceleration output the velocity and the
///     position as its first and second integrals likewise. Without a continuous
///     equivalent the integrals are running sums over the steps. Modal terms
///     enter the integrals by the rectangle rule (their own integral is not a
///     state);
///  3. sensor: the sensor blocks in chain order (gain_error scales C x + D f +
///     modes, then cross_coupling, offset_drift, periodic_disturbance add),
///     t = k Ts from the first sample.
/// Substeps > 1 need the nominal's continuous-time equivalent (d2c_zoh); when it
/// has none (a pole on the negative real axis) one step per sample is used and a
/// warning says so.
/// All blocks act in the nominal's deviation coordinates (inputs minus
/// input_offset, outputs before output_offset is added).
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

#include "sysid/core/state_space.hpp"
#include "sysid/diagnose/physics_block.hpp"

namespace sysid {

/// What an output's sensor measures (DESIGN.md "Model files": output_quantities).
/// Forces inside a mechanical plant act on the actuator's position and velocity,
/// which each quantity gives differently (see the method above); `unknown` is
/// read as a position by the simulation, and diagnose tries the readings.
enum class OutputQuantity { unknown, position, velocity, acceleration, other };

/// "position", "velocity", "acceleration", "other", "unknown".
const char* quantity_name(OutputQuantity q);

/// The quantity named `name` (the four DESIGN.md names); std::invalid_argument otherwise.
OutputQuantity parse_output_quantity(const std::string& name);

/// One quantity per output from one name for every output or one name per output
/// (`--output-quantity`, Python's output_quantity); std::invalid_argument for a
/// wrong count or an unknown name.
std::vector<OutputQuantity> parse_output_quantities(const std::vector<std::string>& names, Eigen::Index outputs);

struct AugmentedModel {
  StateSpace nominal;             ///< discrete (Ts > 0)
  Eigen::VectorXd x0;             ///< nominal initial state; empty = zero
  Eigen::VectorXd input_offset;   ///< m, or empty
  Eigen::VectorXd output_offset;  ///< l, or empty
  std::vector<PhysicsBlock> blocks;
  int substeps = 1;               ///< linear-core steps per sample (>= 1)
  std::vector<OutputQuantity> output_quantities;  ///< one per output, or empty (all unknown)
};

/// Simulates one nominal model with any set of blocks; holds what does not depend
/// on the blocks (the continuous equivalent, the step-h nominal), so a fitter can
/// call simulate() hundreds of times cheaply.
class AugmentedSimulator {
 public:
  /// Preconditions (std::invalid_argument): nominal discrete and valid, substeps >= 1,
  /// x0 empty or of size n, output_quantities empty (all unknown) or one per output.
  AugmentedSimulator(const StateSpace& nominal, int substeps = 1, Eigen::VectorXd x0 = {},
                     std::vector<OutputQuantity> output_quantities = {});

  /// Output (samples x l) for input u (N x m, deviation coordinates), first
  /// `samples` rows (-1: all). Preconditions (std::invalid_argument): u has m
  /// columns; blocks name known kinds with complete, admissible parameters and
  /// channels in range.
  Eigen::MatrixXd simulate(const std::vector<PhysicsBlock>& blocks, const Eigen::Ref<const Eigen::MatrixXd>& u,
                           Eigen::Index samples = -1) const;

  const StateSpace& nominal() const { return m_nominal; }
  int substeps() const { return m_substeps; }
  bool has_continuous_equivalent() const { return m_continuous.has_value(); }
  /// The nominal's continuous-time (ZOH) equivalent, when it exists.
  const std::optional<StateSpace>& continuous_equivalent() const { return m_continuous; }
  const std::vector<std::string>& warnings() const { return m_warnings; }
  /// How output i is read (unknown when not given).
  OutputQuantity output_quantity(Eigen::Index i) const;
  const std::vector<OutputQuantity>& output_quantities() const { return m_quantities; }

 private:
  StateSpace m_nominal;
  std::optional<StateSpace> m_continuous;
  StateSpace m_step;  ///< the nominal at step Ts / substeps
  /// The nominal with the integrator states of the velocity and acceleration
  /// outputs appended, at step Ts / substeps (empty when no output needs one).
  StateSpace m_step_integrated;
  std::vector<Eigen::Index> m_position_state, m_velocity_state;  ///< per output: the appended state holding it, or -1
  int m_substeps = 1;
  Eigen::VectorXd m_x0;
  std::vector<OutputQuantity> m_quantities;
  std::vector<std::string> m_warnings;
};

/// Validates every block of `blocks` against a model with m inputs and l outputs
/// (kind known, every parameter present and admissible, channels in range).
/// Throws std::invalid_argument naming the block and the parameter.
void check_physics_blocks(const std::vector<PhysicsBlock>& blocks, Eigen::Index m, Eigen::Index l, double Ts);

/// simulate of an AugmentedModel on raw inputs (offsets applied both ways).
Eigen::MatrixXd simulate_augmented(const AugmentedModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u);

/// The actuator stage alone (step 1 above), N x m: what reaches the linear core.
Eigen::MatrixXd actuator_output(const std::vector<PhysicsBlock>& blocks, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                double Ts, Eigen::Index samples);

}  // namespace sysid
