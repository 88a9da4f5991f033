#pragma once
/// @file
/// Purpose: fit the parameters of one or several physics blocks (candidates) on
/// top of a nominal model and already accepted blocks, by minimising the
/// simulation error — the fitting stage of `sysid diagnose` (issue 6, scope 3).
///
/// Method: the free parameters are mapped to the unit box (logarithmically where
/// a parameter spans decades) and fitted with NLopt in two stages: a global
/// search over the box (DIRECT-L, Gablonsky and Kelley, J. Global Optim. 21
/// (2001)) started nowhere in particular, then a local derivative-free refinement
/// (BOBYQA, Powell 2009) from the better of the global result and the detector's
/// start. The cost is the simulation error, not the one-step prediction error:
/// the nominal is a simulation model and the report's fit is a simulation fit.
/// Cost = sum over outputs of SSE_i / (rows * var(y_i)), i.e. the mean of
/// (1 - fit_i/100)^2 up to the mean removal.
#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "sysid/diagnose/augmented_model.hpp"
#include "sysid/diagnose/physics_block.hpp"

namespace sysid {

/// A parameter the fitter varies within [lower, upper].
struct FreeParameter {
  std::string name;
  double lower = 0.0, upper = 1.0;
  bool log_scale = false;  ///< fit log(p) (needs lower > 0): for parameters spanning decades
};

/// A physics hypothesis ready to fit: the block with every parameter set (the free
/// ones at the detector's start values) and what the detector saw.
struct Candidate {
  PhysicsBlock block;
  std::vector<FreeParameter> free;
  int substeps = 1;             ///< simulation steps per sample the block needs to be accurate
  double detector_score = 0.0;  ///< fraction of the current residual energy its linearised effect explains
  std::string evidence;         ///< the detector's observation in words
  /// The reading of the outputs the candidate was proposed under (a force
  /// inside the plant when diagnose tries several readings); empty: the model's.
  std::vector<OutputQuantity> output_quantities = {};
};

struct CandidateFitOptions {
  int global_evaluations_per_parameter = 30;  ///< DIRECT-L budget per free parameter (0: no global stage)
  int local_evaluations = 150;                ///< BOBYQA budget
  double relative_tolerance = 1e-6;           ///< BOBYQA stop on the relative cost change
};

struct CandidateFitResult {
  std::vector<Candidate> fitted;  ///< the candidates with their fitted parameters
  double cost = 0.0;              ///< normalised simulation cost at the result (see file comment)
  double start_cost = 0.0;        ///< the same at the start values
  int evaluations = 0;
};

/// Weighted simulation cost of `blocks` on rows [0, rows) (weights: 1/var(y_i)).
double simulation_cost(const AugmentedSimulator& simulator, const std::vector<PhysicsBlock>& blocks,
                       const Eigen::Ref<const Eigen::MatrixXd>& u, const Eigen::Ref<const Eigen::MatrixXd>& y,
                       Eigen::Index rows);

/// Fits the free parameters of `candidates` jointly, with `fixed` blocks held as
/// they are, on rows [0, rows) of (u, y) (deviation coordinates). The result is
/// never worse than the start (the start is kept when no evaluation improves it).
/// Preconditions (std::invalid_argument): bounds ordered, log-scale bounds > 0,
/// 0 < rows <= u.rows() == y.rows().
CandidateFitResult fit_candidates(const AugmentedSimulator& simulator, const std::vector<PhysicsBlock>& fixed,
                                  std::vector<Candidate> candidates, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                  const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::Index rows,
                                  const CandidateFitOptions& options = {});

/// A parameter's coordinate in the unit box of its bounds (logarithmic when
/// log_scale), clamped to [0, 1], and back.
double unit_coordinate(const FreeParameter& p, double value);
double parameter_value(const FreeParameter& p, double z);

struct UnitBoxFit {
  std::vector<double> z;   ///< the best point evaluated
  double cost = 0.0;       ///< its cost
  double start_cost = 0.0;
  int evaluations = 0;
};

/// Minimises cost(z) over [0, 1]^d: DIRECT-L with `global_evaluations` (0: no
/// global stage) from nowhere in particular, then BOBYQA from the best point so
/// far. Returns the best point evaluated, never worse than `start`. A
/// non-finite cost counts as 1e30 (worse than anything).
UnitBoxFit minimise_in_unit_box(const std::function<double(const std::vector<double>&)>& cost, const std::vector<double>& start,
                                int global_evaluations, int local_evaluations, double relative_tolerance);

/// The blocks of `fixed` followed by those of `candidates`.
std::vector<PhysicsBlock> combine_blocks(const std::vector<PhysicsBlock>& fixed, const std::vector<Candidate>& candidates);

}  // namespace sysid
