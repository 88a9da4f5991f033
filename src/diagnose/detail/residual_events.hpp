#pragma once
// Where in time a residual lives: near the velocity reversals of the motion
// (where friction and play act) or near the zero crossings of the command
// (where a dead zone acts) — the evidence that tells friction from a dead zone
// (issue 33, item 2). Both flatten the response; on a velocity-output drive
// driven by a slow stroke the two sets of instants are close, so the evidence
// states both and the fitted alternatives' gains. Internal to src/diagnose.
#include <Eigen/Dense>
#include <string>

namespace sysid {

struct ResidualEvents {
  Eigen::Index reversals = 0, crossings = 0;  ///< sign changes of the velocity / of the command
  Eigen::Index halfwidth = 0;                 ///< samples either side counted as "near"
  double near_reversals = 0.0;                ///< mean square of the residual near reversals / overall
  double near_crossings = 0.0;                ///< the same near the command's zero crossings
  bool tested = false;                        ///< both sets non-empty and distinct from the rest
};

/// Sign changes are counted after a dead band of 1 % of each signal's RMS (noise
/// around zero is not a reversal); near = within `halfwidth` samples (0: 10 % of
/// the median spacing of the reversals, at least 1).
ResidualEvents residual_events(const Eigen::VectorXd& residual, const Eigen::VectorXd& velocity, const Eigen::VectorXd& command,
                               Eigen::Index halfwidth = 0);

/// "the residual before it is 3.1 times its mean square within 2.5 ms of the 22
/// velocity reversals, 1.2 times near the 40 zero crossings of the command".
std::string describe(const ResidualEvents& e, double Ts);

/// The evidence of a kind whose residual lives at the velocity reversals
/// (`at_reversals`: friction) or at the command's zero crossings (a dead zone):
/// describe(), then whether the residual lives where the kind acts or nearer
/// where the other would act.
std::string where_it_lives(const Eigen::VectorXd& residual, const Eigen::VectorXd& velocity, const Eigen::VectorXd& command,
                           double Ts, bool at_reversals);

}  // namespace sysid
