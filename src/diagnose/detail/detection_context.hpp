#pragma once
// What every detector of src/diagnose/kinds/ sees (method in
// include/sysid/diagnose/hypotheses.hpp): the current residual, the output
// weights, the simulation of a probed block, least squares of the residual on
// sensitivities, and the tools several kinds share (a linearised single-parameter
// candidate, the best point of a grid, the nominal's modal basis). Internal to
// src/diagnose.
#include <Eigen/Dense>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "sysid/diagnose/candidate_fit.hpp"
#include "sysid/diagnose/hypotheses.hpp"
#include "sysid/diagnose/physics_kind.hpp"

namespace sysid {

/// The eigen-decomposition of the nominal's continuous equivalent A = V diag(p) V^-1,
/// with C V and V^-1 B: every path's modal residues r = (C V)_ik (V^-1 B)_kj.
/// Empty (no poles) when there is no continuous equivalent or V is (nearly)
/// defective — no reliable residues then.
struct ModalBasis {
  Eigen::VectorXcd poles;
  Eigen::MatrixXcd output_shapes;  ///< C V, l x n
  Eigen::MatrixXcd input_shapes;   ///< V^-1 B, n x m
};

class DetectionContext {
 public:
  /// `reading`: the simulator whose output quantities the plant's forces use
  /// (one of data.plant_readings), nullptr for data.simulator.
  DetectionContext(const DetectionData& data, const DetectionOptions& options, const AugmentedSimulator* reading = nullptr);

  const DetectionData& data() const { return m_data; }
  const DetectionOptions& options() const { return m_options; }
  const AugmentedSimulator& simulator() const { return *m_simulator; }
  Eigen::Index rows() const { return m_rows; }
  Eigen::Index inputs() const { return m_data.u.cols(); }
  Eigen::Index outputs() const { return m_data.y.cols(); }
  double Ts() const { return m_data.Ts; }
  double duration() const { return static_cast<double>(m_rows) * m_data.Ts; }
  const Eigen::MatrixXd& residual() const { return m_residual; }
  const ModalBasis& nominal_basis() const { return m_basis; }
  /// The quantity the simulator reads output i as (position when unknown).
  OutputQuantity quantity(long output) const;

  /// The signal weighted per output (1 / std(y_i)) and stacked output by output.
  Eigen::VectorXd weighted(const Eigen::MatrixXd& signal) const;
  /// Weighted change of the output when `block` is added to the accepted ones.
  Eigen::VectorXd effect(const PhysicsBlock& block) const;
  /// Fraction of the residual energy explained by adding `change` as it is.
  double explained_as_is(const Eigen::VectorXd& change) const;
  /// Least squares of the residual on the columns of G: coefficients and the
  /// fraction of the residual energy they explain (QR, no normal equations).
  std::pair<Eigen::VectorXd, double> regress(const Eigen::MatrixXd& G) const;
  /// Columns: the weighted output change per unit of each probed parameter, each
  /// probe taken alone from `block` (whose effect must vanish as it is) by its step.
  Eigen::MatrixXd sensitivities(const PhysicsBlock& block, const std::vector<std::pair<std::string, double>>& probes) const;

  /// The current simulation's motion at output i as the reading has it: position
  /// and velocity (a velocity output integrated once for the position, an
  /// acceleration output once and twice; the running integrals have their mean
  /// removed: only their shape sizes the detectors' steps).
  Eigen::VectorXd position(long output) const;
  Eigen::VectorXd velocity(long output) const;

  /// The candidate a single-parameter effect vanishing at p0 gives: the
  /// sensitivity regression's step from p0, clamped to the bounds.
  Candidate linearised(PhysicsBlock block, const std::string& name, double p0, double delta, FreeParameter bound,
                       int substeps, const std::string& what) const;
  /// The grid point whose effect, taken as is, explains most of the residual
  /// (scores start below every value: an effect larger than the residual
  /// explains a negative fraction, and the least bad point is still the start).
  Candidate best_as_is(const std::vector<PhysicsBlock>& grid) const;

 private:
  const DetectionData& m_data;
  const DetectionOptions& m_options;
  const AugmentedSimulator* m_simulator;
  Eigen::Index m_rows = 0;
  Eigen::VectorXd m_output_weight;
  Eigen::MatrixXd m_residual;
  double m_residual_energy = 0.0;
  ModalBasis m_basis;
};

/// The motion a simulated output y (one column) carries, read as `q`: its
/// velocity and its position (a velocity integrated once for the position, an
/// acceleration once and twice; running integrals with their mean removed, a
/// position differenced for the velocity).
Eigen::VectorXd reading_velocity(const Eigen::VectorXd& y, OutputQuantity q, double Ts);
Eigen::VectorXd reading_position(const Eigen::VectorXd& y, OutputQuantity q, double Ts);

/// A block of `kind` on the path input -> output, every parameter 0.
PhysicsBlock make_block(const std::string& kind, long input, long output);

/// Root mean square of x (0 for an empty x).
double rms(const Eigen::VectorXd& x);

/// Input j varies over the detection rows (propose_candidates proposes no
/// actuator effect or plant force on a constant input).
bool varies(const DetectionContext& c, long input);

/// "12.3 %" for a fraction 0.123.
std::string percent(double fraction);

/// The smallest positive normal double (a floor for scales and bounds).
inline constexpr double kTinyScale = std::numeric_limits<double>::min();

}  // namespace sysid
