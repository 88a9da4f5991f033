#pragma once
/// @file
/// Purpose: a nominal discrete state-space model augmented with physics blocks
/// (physics_block.hpp), and its simulation. This is what `sysid diagnose` writes
/// as `"type": "augmented"` and what `sysid simulate` runs.
///
/// Method (per sample k, input held over the sample as the nominal's ZOH assumes):
///  1. actuator: u_j -> saturation -> time_delay (fractional: linear interpolation
///     between samples, rest before the record) -> deadzone -> backlash (play
///     operator) -> hysteresis (discrete Bouc-Wen: h[k+1] = h[k] + alpha du -
///     beta |du| h[k] - gamma du |h[k]|, force = u - h; Ismail, Ikhouane and
///     Rodellar, Arch. Comput. Methods Eng. 16 (2009), eq. (6) with n = 1);
///  2. linear core, stepped `substeps` times per sample at h = Ts/substeps:
///     the nominal (x+ = Phi x + Gamma f), an input lag per channel (first order,
///     its exact mean over the step is the force held), a modal term per missing
///     mode (s^2 + 2 zeta w s + w^2 in parallel, output static_gain w^2 q +
///     velocity_gain w q', exactly ZOH-discretised); the plant force
///     f_j = drive_j - sum of plant feedback forces at j, where friction
///     level tanh(v/velocity_scale) and cubic stiffness coefficient y^3 are
///     evaluated at the start of each step from the collocated output's position
///     y_i = C x + modes and velocity (exact, C (A_c x + B_c f), when the nominal
///     has a continuous equivalent, otherwise a backward difference);
///  3. sensor: y_i = ratio (C x + D f + modes) + cross_coupling + offset +
///     slope t + amplitude sin(2 pi f t + phase), t = k Ts from the first sample.
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

struct AugmentedModel {
  StateSpace nominal;             ///< discrete (Ts > 0)
  Eigen::VectorXd x0;             ///< nominal initial state; empty = zero
  Eigen::VectorXd input_offset;   ///< m, or empty
  Eigen::VectorXd output_offset;  ///< l, or empty
  std::vector<PhysicsBlock> blocks;
  int substeps = 1;               ///< linear-core steps per sample (>= 1)
};

/// Simulates one nominal model with any set of blocks; holds what does not depend
/// on the blocks (the continuous equivalent, the step-h nominal), so a fitter can
/// call simulate() hundreds of times cheaply.
class AugmentedSimulator {
 public:
  /// Preconditions (std::invalid_argument): nominal discrete and valid, substeps >= 1,
  /// x0 empty or of size n.
  AugmentedSimulator(const StateSpace& nominal, int substeps = 1, Eigen::VectorXd x0 = {});

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

 private:
  StateSpace m_nominal;
  std::optional<StateSpace> m_continuous;
  StateSpace m_step;  ///< the nominal at step Ts / substeps
  int m_substeps = 1;
  Eigen::VectorXd m_x0;
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
