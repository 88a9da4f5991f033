// backlash: play in the actuation (a play operator on the command).
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"

#include <algorithm>

namespace sysid {

namespace {

class Backlash final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    static const BlockKindInfo i{"backlash", BlockStage::actuator, {"width"}, {"width"}, "play (backlash) in the actuation",
                                 {{"width"}}, 3};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index, double) const override {
    if (!(b.param("width") >= 0.0)) throw std::invalid_argument("backlash: need width >= 0");
  }
  /// Play operator: the output follows the input at a distance of half the width
  /// and holds while the input moves inside the play.
  void actuate(const PhysicsBlock& b, double, Eigen::Ref<Eigen::VectorXd> w) const override {
    if (w.size() == 0) return;
    const double half = 0.5 * b.param("width");
    double held = std::clamp(0.0, w[0] - half, w[0] + half);
    for (Eigen::Index k = 0; k < w.size(); ++k) {
      held = std::clamp(held, w[k] - half, w[k] + half);
      w[k] = held;
    }
  }
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    const Eigen::VectorXd uj = c.data().u.col(j);
    out.push_back(c.linearised(make_block("backlash", j, i), "width", 0.0, 0.01 * rms(uj), {"width", 0.0, uj.cwiseAbs().maxCoeff()},
                               1, "play at input reversals"));
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "The actuation of " + s.input + " has play (backlash) of total width " + format_number(b.param("width"), 3) +
           " (input units).";
  }
};

}  // namespace

const PhysicsKind& backlash_kind() {
  static const Backlash kind;
  return kind;
}

}  // namespace sysid
