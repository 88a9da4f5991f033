// input_lag: a first-order low-pass between the command and the plant force
// (an amplifier's bandwidth, a valve), part of the linear core.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"
#include "sysid/core/math_constants.hpp"

#include <algorithm>
#include <cmath>

namespace sysid {

namespace {

class InputLag final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    // Absent when the corner is at infinity: 1 / corner is tested against 0.
    static const BlockKindInfo i{"input_lag", BlockStage::actuator, {"corner_hz"}, {"corner_hz"},
                                 "a first-order lag in the actuator", {{"corner_hz", 0.0, nullptr, true}}};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index, double) const override {
    if (!(b.param("corner_hz") > 0.0)) throw std::invalid_argument("input_lag: need corner_hz > 0");
  }
  double lag_corner_hz(const PhysicsBlock& b) const override { return b.param("corner_hz"); }

  /// A lag of time constant tau acts like -tau du/dt at low frequency; the
  /// sensitivity is taken in tau and the start converted to a corner.
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    const double Ts = c.Ts();
    PhysicsBlock b = make_block("input_lag", j, i);
    const double tau_probe = 0.25 * Ts;
    b.params["corner_hz"] = 1.0 / (kTwoPi * tau_probe);
    const Eigen::VectorXd g = c.effect(b) / tau_probe;
    const auto [coef, explained] = c.regress(g);
    const double lo = 0.002 / Ts, hi = 1.0 / Ts;
    const double tau = std::max(coef[0], 1.0 / (kTwoPi * hi));
    b.params["corner_hz"] = std::clamp(1.0 / (kTwoPi * tau), lo, hi);
    out.push_back({b, {{"corner_hz", lo, hi, true}}, 1, std::max(0.0, explained),
                   "a low-passed input explains " + percent(std::max(0.0, explained)) + " (linearised)"});
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "The actuation of " + s.input + " lags like a first-order low-pass with a corner at " +
           format_number(b.param("corner_hz"), 4) + " Hz that the simulation lacks.";
  }
};

}  // namespace

const PhysicsKind& input_lag_kind() {
  static const InputLag kind;
  return kind;
}

}  // namespace sysid
