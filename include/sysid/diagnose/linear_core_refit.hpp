#pragma once
/// @file
/// Purpose: refit a nominal model's linear dynamics together with the physics
/// blocks `sysid diagnose` found, for a nominal that was itself identified from
/// the nonlinear machine (DiagnoseOptions::refit_nominal).
///
/// Why: a linear model identified on data from a nonlinear machine is its best
/// linear approximation, which holds a compromise of the nonlinearity — a
/// saturating store leaves the identified poles and gains between those of the
/// free and the clipped regime. Once the nonlinearity is a block, that
/// compromise is a bias: the linear part should be what the data say *with*
/// the block in the loop (the reasoning of block-oriented identification,
/// Schoukens and Ljung, "Nonlinear system identification: a user-oriented road
/// map", IEEE Control Systems 39 (2019), sec. "grey-box"). cubic_stiffness
/// carries its own linear term for the same reason (physics_block.hpp).
///
/// Method: the nominal is brought to real modal form, A = blockdiag(p_k or
/// [[sigma, omega], [-omega, sigma]]), B_m = T^-1 B, C_m = C T, x0_m = T^-1 x0
/// (T from the eigenvectors); the free parameters are every real pole (within a
/// factor of two of its time constant), every complex pair's modulus (the same)
/// and angle (+-25 %), B_m, D and x0_m (boxes around the start sized by each
/// state's RMS on the record), plus the blocks' own free parameters; C_m is
/// fixed (it only fixes each mode's scale against B_m). The simulation cost of
/// candidate_fit.hpp is minimised by BOBYQA from the start (no global stage: the
/// start is the identified model). Poles stay inside the unit circle by the
/// bounds. Not offered when T is ill-conditioned (a defective A).
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "sysid/core/state_space.hpp"
#include "sysid/diagnose/candidate_fit.hpp"

namespace sysid {

struct LinearCoreRefitOptions {
  int local_evaluations = 4000;      ///< BOBYQA budget (it stops earlier on the tolerance: ~2 500 for 10 parameters)
  double relative_tolerance = 1e-8;  ///< BOBYQA stop on the relative cost change
  int max_order = 12;                ///< larger nominals are not refitted (too many parameters)
};

struct LinearCoreRefitResult {
  bool refitted = false;             ///< false: not attempted (reason in `warnings`)
  StateSpace model;                  ///< the refitted nominal, real modal form
  Eigen::VectorXd x0;                ///< its initial state
  std::vector<Candidate> blocks;     ///< the candidates with their refitted parameters
  Eigen::VectorXcd poles_before, poles_after;  ///< discrete poles
  double start_cost = 0.0, cost = 0.0;
  int evaluations = 0;
  std::vector<std::string> warnings;
};

/// Refits `nominal` (discrete, initial state x0, empty = zero) jointly with the
/// free parameters of `candidates`, `fixed` blocks held, on rows [0, rows) of
/// (u, y) in deviation coordinates, simulating with `substeps` steps per sample
/// and the outputs read as `output_quantities` say (empty: unknown). Never worse than the start on those rows.
/// Preconditions (std::invalid_argument): 0 < rows <= u.rows() == y.rows(), sizes
/// match the nominal.
LinearCoreRefitResult refit_linear_core(const StateSpace& nominal, const Eigen::VectorXd& x0,
                                        const std::vector<PhysicsBlock>& fixed, const std::vector<Candidate>& candidates,
                                        const Eigen::Ref<const Eigen::MatrixXd>& u, const Eigen::Ref<const Eigen::MatrixXd>& y,
                                        Eigen::Index rows, int substeps, const LinearCoreRefitOptions& options = {},
                                        const std::vector<OutputQuantity>& output_quantities = {});

}  // namespace sysid
