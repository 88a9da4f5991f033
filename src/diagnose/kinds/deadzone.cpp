// deadzone: no actuation while the command is within +-width/2 of zero, the
// command less width/2 beyond.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"
#include "diagnose/detail/residual_events.hpp"

namespace sysid {

namespace {

class Deadzone final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    static const BlockKindInfo i{"deadzone", BlockStage::actuator, {"width"}, {"width"}, "a dead zone in the actuation",
                                 {{"width"}}, 2};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index, double) const override {
    if (!(b.param("width") >= 0.0)) throw std::invalid_argument("deadzone: need width >= 0");
  }
  void actuate(const PhysicsBlock& b, double, Eigen::Ref<Eigen::VectorXd> w) const override {
    const double half = 0.5 * b.param("width");
    for (Eigen::Index k = 0; k < w.size(); ++k) {
      const double v = w[k];
      w[k] = v > half ? v - half : (v < -half ? v + half : 0.0);
    }
  }
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    const Eigen::VectorXd uj = c.data().u.col(j);
    out.push_back(c.linearised(make_block("deadzone", j, i), "width", 0.0, 0.01 * rms(uj), {"width", 0.0, uj.cwiseAbs().maxCoeff()},
                               1, "a dead band around zero input"));
  }
  /// Friction and a dead zone both flatten the response; the residual they
  /// explain sits at different instants (residual_events.hpp).
  std::string where_evidence(const PhysicsBlock&, const FindingSignals& s) const override {
    return where_it_lives(s.residual_before, s.velocity, s.command, s.Ts, /*at_reversals=*/false);
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "The actuation of " + s.input + " has a dead zone of total width " + format_number(b.param("width"), 3) + " (input units).";
  }
};

}  // namespace

const PhysicsKind& deadzone_kind() {
  static const Deadzone kind;
  return kind;
}

}  // namespace sysid
