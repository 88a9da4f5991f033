// coulomb_friction: a force of constant size opposing the velocity at the
// actuator, possibly of another size in each direction (a drive's seals, a
// guide's preload, a belt's tension). Smooth sign: level tanh(v / velocity_scale),
// so the simulation stays an ODE with bounded slope.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"
#include "diagnose/detail/residual_events.hpp"
#include "sysid/diagnose/parameter_uncertainty.hpp"

#include <algorithm>
#include <cmath>

namespace sysid {

namespace {

/// parameters: level, velocity_scale, asymmetry r in [-1, 1]. The force opposing
/// the motion is level (1 + r sign v) tanh(v / s): level (1 + r) moving positive,
/// level (1 - r) moving negative (DESIGN.md's level_positive, level_negative; their
/// mean is level). r is a fraction so that neither direction's level can turn
/// negative: friction never pushes along the motion (a force that does, in one
/// direction, is a constant force beside the friction — constant_force).
double friction_law(const double* p, double /*position*/, double velocity) {
  const double t = std::tanh(velocity / p[1]);
  return -p[0] * (t + p[2] * std::abs(t));
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
    if (!(std::abs(b.param("asymmetry")) <= 1.0)) throw std::invalid_argument("coulomb_friction: need asymmetry in [-1, 1]");
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
    const double level = b.param("level"), r = b.param("asymmetry");
    if (r == 0.0) return {{"level", level}};
    return {{"level", level}, {"level_positive", level * (1.0 + r)}, {"level_negative", level * (1.0 - r)}};
  }

  /// The sensitivities of a symmetric friction force and of a force of the same
  /// size in one direction only (both linear in the force at zero friction):
  /// least squares gives the level and the asymmetry's start, and the score.
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    const Eigen::VectorXd uj = c.data().u.col(j);
    const double u_rms = rms(uj), u_max = uj.cwiseAbs().maxCoeff(), probe = 0.01 * u_rms;
    PhysicsBlock b = make_block("coulomb_friction", j, i);
    b.params["velocity_scale"] = std::max(c.options().friction_velocity_fraction * rms(c.velocity(i)), kTinyScale);
    PhysicsBlock one_sided = b;
    one_sided.params["level"] = probe;
    one_sided.params["asymmetry"] = 1.0;
    Eigen::MatrixXd G(c.rows() * c.outputs(), 2);
    G.col(0) = c.sensitivities(b, {{"level", probe}});
    G.col(1) = (c.effect(one_sided) / probe - G.col(0)).eval();  // the |tanh| force per unit of level x asymmetry
    const auto [coef, explained] = c.regress(G);
    const auto [symmetric, symmetric_explained] = c.regress(G.col(0));
    // Where both explain alike, the symmetric start (the asymmetry is an optional term).
    const bool asymmetric = explained > symmetric_explained + 0.01 && coef[0] > 0.0;
    b.params["level"] = std::clamp(asymmetric ? coef[0] : symmetric[0], 0.0, u_max);
    b.params["asymmetry"] = asymmetric ? std::clamp(coef[1] / coef[0], -1.0, 1.0) : 0.0;
    const double score = std::max(0.0, asymmetric ? explained : symmetric_explained);
    out.push_back({b, {{"level", 0.0, u_max}, {"asymmetry", -1.0, 1.0}}, c.simulator().substeps(), score,
                   "a force opposing the " + std::string(quantity_name(c.quantity(i))) + " reading's velocity explains " +
                       percent(score) + " of the residual energy (linearised" +
                       (asymmetric ? ", different in each direction)" : ")")});
  }

  /// level_positive = level (1 + r), level_negative = level (1 - r): their
  /// variances from the pair's covariance (first order: gradient (1 +- r, +-level)).
  std::map<std::string, double> reported_uncertainty(const Candidate& fitted, const CandidateUncertainty& u) const override {
    std::map<std::string, double> out = PhysicsKind::reported_uncertainty(fitted, u);
    if (!out.count("level_positive")) return out;
    Eigen::Index level = -1, asymmetry = -1;
    for (std::size_t k = 0; k < fitted.free.size(); ++k) {
      if (fitted.free[k].name == "level") level = static_cast<Eigen::Index>(k);
      if (fitted.free[k].name == "asymmetry") asymmetry = static_cast<Eigen::Index>(k);
    }
    if (level < 0 || asymmetry < 0) return out;
    const double l = fitted.block.param("level"), r = fitted.block.param("asymmetry");
    const Eigen::Matrix2d C{{u.covariance(level, level), u.covariance(level, asymmetry)},
                            {u.covariance(asymmetry, level), u.covariance(asymmetry, asymmetry)}};
    for (const double sign : {1.0, -1.0}) {
      const Eigen::Vector2d gradient(1.0 + sign * r, sign * l);
      out[sign > 0 ? "level_positive" : "level_negative"] = std::sqrt(std::max(0.0, gradient.dot(C * gradient)));
    }
    return out;
  }
  /// Friction and a dead zone both flatten the response; the residual they
  /// explain sits at different instants (residual_events.hpp).
  std::string where_evidence(const PhysicsBlock&, const FindingSignals& s) const override {
    return where_it_lives(s.residual_before, s.velocity, s.command, s.Ts, /*at_reversals=*/true);
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    const double level = b.param("level"), r = b.param("asymmetry");
    const std::string size = r == 0.0 ? format_number(level, 3) + " (input units)"
                                      : format_number(level * (1.0 + r), 3) + " moving positive and " + format_number(level * (1.0 - r), 3) +
                                            " moving negative (input units; mean " + format_number(level, 3) + ")";
    return "A Coulomb friction force of " + size + " opposes the motion at " + s.output + "; it shows near velocity reversals.";
  }
};

}  // namespace

const PhysicsKind& coulomb_friction_kind() {
  static const CoulombFriction kind;
  return kind;
}

}  // namespace sysid
