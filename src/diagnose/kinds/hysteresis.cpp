// hysteresis: a discrete Bouc-Wen loop in the actuator (piezo stacks, magnetic
// actuators): h[k+1] = h[k] + alpha du - beta |du| h[k] - gamma du |h[k]|,
// force = u - h; Ismail, Ikhouane and Rodellar, Arch. Comput. Methods Eng. 16
// (2009), eq. (6) with n = 1.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"

#include <algorithm>
#include <cmath>

namespace sysid {

namespace {

class Hysteresis final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    // alpha scales the loop: none without it.
    static const BlockKindInfo i{"hysteresis", BlockStage::actuator, {"alpha", "beta", "gamma"}, {},
                                 "hysteresis (Bouc-Wen) in the actuator", {{"alpha"}}, 4};
    return i;
  }
  void actuate(const PhysicsBlock& b, double, Eigen::Ref<Eigen::VectorXd> w) const override {
    if (w.size() == 0) return;
    const double alpha = b.param("alpha"), beta = b.param("beta"), gamma = b.param("gamma");
    double h = 0.0, previous = w[0];
    for (Eigen::Index k = 1; k < w.size(); ++k) {
      const double du = w[k] - previous;
      previous = w[k];
      h += alpha * du - beta * std::abs(du) * h - gamma * du * std::abs(h);
      w[k] -= h;
    }
  }
  /// Loop width about alpha / (beta + gamma) in input units; grid over the
  /// amplitude alpha and the loop's saturation scale.
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    const Eigen::VectorXd uj = c.data().u.col(j);
    const double u_range = uj.maxCoeff() - uj.minCoeff();
    std::vector<PhysicsBlock> grid;
    for (double alpha : {0.01, 0.03, 0.1, 0.3})
      for (double shape : {1.0, 4.0, 16.0}) {
        PhysicsBlock b = make_block("hysteresis", j, i);
        b.params["alpha"] = alpha;
        b.params["beta"] = shape / u_range;
        b.params["gamma"] = shape / u_range;
        grid.push_back(b);
      }
    Candidate best = c.best_as_is(grid);
    best.free = {{"alpha", 0.0, 0.6}, {"beta", 0.05 / u_range, 200.0 / u_range, true}, {"gamma", -50.0 / u_range, 200.0 / u_range}};
    best.detector_score = std::max(0.0, best.detector_score);
    best.evidence = "a hysteresis loop (Bouc-Wen) in the actuator explains " + percent(best.detector_score);
    out.push_back(best);
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "The actuator of " + s.input + " shows hysteresis (Bouc-Wen alpha " + format_number(b.param("alpha"), 3) + ").";
  }
};

}  // namespace

const PhysicsKind& hysteresis_kind() {
  static const Hysteresis kind;
  return kind;
}

}  // namespace sysid
