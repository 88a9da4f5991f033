// cubic_stiffness: a hardening (or softening) spring, force coefficient p^3 +
// linear_coefficient p at the actuator's position p (physics_block.hpp: the
// linear term takes back the average stiffness a best-linear nominal holds).
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"

#include <algorithm>
#include <cmath>

namespace sysid {

namespace {

double cubic_law(const double* p, double position, double /*velocity*/) {
  return -(p[0] * position * position + p[1]) * position;
}

class CubicStiffness final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    // The cubic coefficient defines it; the linear term alone is a stiffness
    // error (mode_shift, gain_error), never this physics.
    static const BlockKindInfo i{"cubic_stiffness", BlockStage::plant_feedback, {"coefficient", "linear_coefficient"},
                                 {"coefficient"}, "a hardening (cubic) stiffness", {{"coefficient"}}};
    return i;
  }
  bool plant_force(const PhysicsBlock& b, PlantForce& f) const override {
    f = {b.input, b.output, cubic_law, {b.param("coefficient"), b.param("linear_coefficient"), 0.0, 0.0}};
    return true;
  }
  /// Two sensitivities, the cubic and the linear stiffness; both enter the force
  /// linearly, so least squares gives the start. Scored by what the cubic adds
  /// beyond a linear stiffness change.
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    const double u_max = c.data().u.col(j).cwiseAbs().maxCoeff();
    const double p_peak = std::max(c.position(i).cwiseAbs().maxCoeff(), kTinyScale);
    const double reach = u_max / (p_peak * p_peak * p_peak), linear_reach = u_max / p_peak;
    PhysicsBlock b = make_block("cubic_stiffness", j, i);
    const Eigen::MatrixXd G =
        c.sensitivities(b, {{"coefficient", 0.01 * reach}, {"linear_coefficient", 0.01 * linear_reach}});
    const auto [coef, explained] = c.regress(G);
    const auto [linear_only, linear_explained] = c.regress(G.col(1));
    (void)linear_only;
    b.params["coefficient"] = std::clamp(coef[0], -reach, reach);
    b.params["linear_coefficient"] = std::clamp(coef[1], -linear_reach, linear_reach);
    const double score = std::max(0.0, explained - std::max(0.0, linear_explained));
    out.push_back({b, {{"coefficient", -reach, reach}, {"linear_coefficient", -linear_reach, linear_reach}},
                   c.simulator().substeps(), score,
                   "a force growing with the cube of the " + std::string(quantity_name(c.quantity(i))) +
                       " reading's position explains " + percent(score) + " beyond a linear stiffness change (linearised)"});
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return std::string(b.param("coefficient") >= 0 ? "A hardening" : "A softening") + " cubic stiffness of " +
           format_number(b.param("coefficient"), 4) + " (input units per position unit cubed) acts at " + s.output +
           "; it shows at the largest amplitudes.";
  }
};

}  // namespace

const PhysicsKind& cubic_stiffness_kind() {
  static const CubicStiffness kind;
  return kind;
}

}  // namespace sysid
