// coulomb_friction: a force of constant size opposing the velocity at the
// actuator, possibly of another size in each direction (a drive's seals, a
// guide's preload, a belt's tension). Smooth sign: level tanh(v / velocity_scale),
// so the simulation stays an ODE with bounded slope.
#include "diagnose/detail/detection_context.hpp"

#include <algorithm>
#include <cmath>

namespace sysid {

namespace {

/// parameters: level, velocity_scale, asymmetry. The force opposing the motion is
/// (level + asymmetry sign v) tanh(v / s): level + asymmetry moving positive,
/// level - asymmetry moving negative (DESIGN.md's level_positive, level_negative).
double friction_law(const double* p, double /*position*/, double velocity) {
  const double t = std::tanh(velocity / p[1]);
  return -(p[0] * t + p[2] * std::abs(t));
}

class CoulombFriction final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    // asymmetry was added after the first files: optional (0) in files. It is an
    // optional term (set to 0 when the data do not show it): see optional_terms.
    static const BlockKindInfo i{"coulomb_friction", BlockStage::plant_feedback, {"level", "velocity_scale", "asymmetry"},
                                 {"level"}, "Coulomb friction opposing the motion", {{"level"}}, 0, {{"asymmetry"}}};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index, double) const override {
    if (!(b.param("velocity_scale") > 0.0)) throw std::invalid_argument("coulomb_friction: need velocity_scale > 0");
  }
  bool optional_default(const std::string& name, double& value) const override {
    if (name != "asymmetry") return false;
    value = 0.0;
    return true;
  }
  bool plant_force(const PhysicsBlock& b, PlantForce& f) const override {
    f = {b.input, b.output, friction_law, {b.param("level"), b.param("velocity_scale"), b.param("asymmetry"), 0.0}};
    return true;
  }
  /// DESIGN.md: level, and level_positive / level_negative when the directions differ.
  std::map<std::string, double> reported(const PhysicsBlock& b) const override {
    const double level = b.param("level"), asymmetry = b.param("asymmetry");
    if (asymmetry == 0.0) return {{"level", level}};
    return {{"level", level}, {"level_positive", level + asymmetry}, {"level_negative", level - asymmetry}};
  }

  /// The level's and the asymmetry's sensitivities at zero friction (both enter
  /// the force linearly): least squares gives the start and the score.
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    if (!varies(c, j)) return;
    const Eigen::VectorXd uj = c.data().u.col(j);
    const double u_rms = rms(uj), u_max = uj.cwiseAbs().maxCoeff();
    PhysicsBlock b = make_block("coulomb_friction", j, i);
    b.params["velocity_scale"] = std::max(c.options().friction_velocity_fraction * rms(c.velocity(i)), kTinyScale);
    const Eigen::MatrixXd G = c.sensitivities(b, {{"level", 0.01 * u_rms}, {"asymmetry", 0.01 * u_rms}});
    const auto [coef, explained] = c.regress(G);
    const auto [symmetric, symmetric_explained] = c.regress(G.col(0));
    // Where both explain alike, the symmetric start (the asymmetry is an optional term).
    const bool asymmetric = explained > symmetric_explained + 0.01;
    b.params["level"] = std::clamp(asymmetric ? coef[0] : symmetric[0], 0.0, u_max);
    b.params["asymmetry"] = asymmetric ? std::clamp(coef[1], -b.params["level"], b.params["level"]) : 0.0;
    const double score = std::max(0.0, asymmetric ? explained : symmetric_explained);
    out.push_back({b, {{"level", 0.0, u_max}, {"asymmetry", -u_max, u_max}}, c.simulator().substeps(), score,
                   "a force opposing the " + std::string(quantity_name(c.quantity(i))) + " reading's velocity explains " +
                       percent(score) + " of the residual energy (linearised" +
                       (asymmetric ? ", different in each direction)" : ")")});
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    const double level = b.param("level"), asymmetry = b.param("asymmetry");
    const std::string size = asymmetry == 0.0
                                 ? fixed(level, 3) + " (input units)"
                                 : fixed(level + asymmetry, 3) + " moving positive and " + fixed(level - asymmetry, 3) +
                                       " moving negative (input units; mean " + fixed(level, 3) + ")";
    return "A Coulomb friction force of " + size + " opposes the motion at " + s.output + "; it shows near velocity reversals.";
  }
};

}  // namespace

const PhysicsKind& coulomb_friction_kind() {
  static const CoulombFriction kind;
  return kind;
}

}  // namespace sysid
