#pragma once
/// @file
/// Purpose: one kind of physics that `sysid diagnose` can add to a nominal model,
/// as one unit: its description (physics_block.hpp BlockKindInfo), the admissible
/// values of its parameters, its part in the augmented simulation, its detector
/// and its sentence in the report. Each kind lives in its own file,
/// src/diagnose/kinds/<kind>.cpp, and is registered by one line in
/// src/diagnose/kinds/registry.cpp; nothing else names a kind.
///
/// The simulation (augmented_model.hpp) asks each block for its part by stage:
/// - actuator: `actuate` transforms the command of the block's input, the blocks
///   taken in `info().chain_order` (saturation, delay, dead zone, play,
///   hysteresis: the amplifier first, then the transport, then the mechanics);
/// - linear core: `lag_corner_hz` (a first-order lag of the drive),
///   `parallel_modes` (modal terms beside the nominal), `plant_force` (a force
///   the plant itself exerts at the block's input, from the motion at its
///   output: position and velocity read according to the output's quantity);
/// - sensor: `sense` acts on the simulated outputs, in chain order.
/// Detectors see the current residual through DetectionContext
/// (src/diagnose/detail/detection_context.hpp) and add Candidates.
#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

#include "sysid/core/state_space.hpp"
#include "sysid/diagnose/physics_block.hpp"

namespace sysid {

struct Candidate;
struct CandidateUncertainty;
class DetectionContext;

/// A modal term in parallel with the nominal path from plant force `input` to
/// output `output`: (static_gain w^2 + velocity_gain w s) / (s^2 + 2 zeta w s + w^2).
struct ParallelMode {
  long input = 0, output = 0;
  double freq_hz = 0.0, damping = 0.0, static_gain = 0.0, velocity_gain = 0.0;
};

/// A force the plant exerts on itself at the block's input, as a compiled law:
/// force = law(parameters, position, velocity) at the block's output, added to
/// the drive (friction returns a force opposing the velocity). The parameters are
/// read from the block once per simulation (a map lookup per step would cost more
/// than the step).
struct PlantForce {
  long input = 0, output = 0;
  double (*law)(const double* parameters, double position, double velocity) = nullptr;
  double parameters[4] = {0.0, 0.0, 0.0, 0.0};
  double operator()(double position, double velocity) const { return law(parameters, position, velocity); }
};

/// What the sensor stage may read: the nominal, the drive reaching the linear
/// core (N x m) and the sample times from the first sample.
struct SensorInputs {
  const StateSpace& nominal;
  const Eigen::MatrixXd& drive;
  const Eigen::VectorXd& time_s;
};

/// What a fitted finding's evidence may look at (estimation rows): the residual
/// before it, the motion at its output as simulated before it (velocity per the
/// output's reading), the command at its input.
struct FindingSignals {
  const Eigen::VectorXd& residual_before;
  const Eigen::VectorXd& velocity;
  const Eigen::VectorXd& command;
  double Ts = 0.0;
};

/// Channel names and the sample time, for a finding's sentence.
struct SummaryContext {
  std::string input, output;  ///< the block's channel names
  double Ts = 0.0;
};

class PhysicsKind {
 public:
  virtual ~PhysicsKind() = default;
  virtual const BlockKindInfo& info() const = 0;

  /// Throws std::invalid_argument naming the parameter when a value is not
  /// admissible in a model with `inputs` inputs and `outputs` outputs (channels
  /// in range and finiteness are checked for every kind before this).
  virtual void check(const PhysicsBlock& /*block*/, Eigen::Index /*inputs*/, Eigen::Index /*outputs*/, double /*Ts*/) const {}
  /// The value of a parameter added to the kind after files with it were written
  /// (keeping those files' meaning); false when `name` has none.
  virtual bool optional_default(const std::string& /*name*/, double& /*value*/) const { return false; }

  /// Actuator stage: the command of block.input, N samples, in place.
  virtual void actuate(const PhysicsBlock& /*block*/, double /*Ts*/, Eigen::Ref<Eigen::VectorXd> /*command*/) const {}
  /// Linear core: the corner of a first-order lag of the drive (0: none).
  virtual double lag_corner_hz(const PhysicsBlock& /*block*/) const { return 0.0; }
  /// Linear core: modal terms in parallel with the nominal.
  virtual std::vector<ParallelMode> parallel_modes(const PhysicsBlock& /*block*/) const { return {}; }
  /// Linear core: the plant's own force law, when the kind is one (stage plant_feedback).
  virtual bool plant_force(const PhysicsBlock& /*block*/, PlantForce& /*force*/) const { return false; }
  /// Sensor stage: the simulated outputs (N x l), in place.
  virtual void sense(const PhysicsBlock& /*block*/, const SensorInputs& /*in*/, Eigen::Ref<Eigen::MatrixXd> /*y*/) const {}

  /// Whether the kind's force reads the motion (position, velocity) at its
  /// output, so that diagnose proposes it once per reading of an output whose
  /// quantity is unknown. True for the plant's forces that do.
  virtual bool reads_motion() const { return info().stage == BlockStage::plant_feedback; }
  /// The DESIGN.md report parameters of a fitted block and their values (default:
  /// info().reported as they are).
  virtual std::map<std::string, double> reported(const PhysicsBlock& block) const;
  /// The standard error of each reported parameter of a fitted candidate, from
  /// its free parameters' covariance (default: a free parameter's own, 0 for a
  /// held one — a nominal frequency is not estimated).
  virtual std::map<std::string, double> reported_uncertainty(const Candidate& fitted, const CandidateUncertainty& u) const;

  /// Candidates of this kind on the path input -> output (the channels the
  /// kind's stage asks for: see propose_candidates), scored on the residual.
  virtual void propose(const DetectionContext& context, long input, long output, std::vector<Candidate>& out) const = 0;
  /// Where in time the residual this kind explains lives, in words, for kinds
  /// that another kind can mimic (friction at velocity reversals, a dead zone at
  /// the command's zero crossings); empty for the others.
  virtual std::string where_evidence(const PhysicsBlock& /*block*/, const FindingSignals& /*signals*/) const { return {}; }
  /// One sentence in plain engineering words about a fitted block.
  virtual std::string summary(const PhysicsBlock& block, const SummaryContext& context) const = 0;
};

/// Every kind, in DESIGN.md order (kinds added later at the end).
const std::vector<const PhysicsKind*>& physics_kinds();

/// The kind named `kind`; std::invalid_argument for an unknown name.
const PhysicsKind& physics_kind(const std::string& kind);

}  // namespace sysid
