// time_delay: a transport or computation delay between the command and the
// actuation; fractional delays interpolate linearly between samples.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"

#include <algorithm>
#include <cmath>

namespace sysid {

namespace {

class TimeDelay final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    static const BlockKindInfo i{"time_delay", BlockStage::actuator, {"delay_s"}, {"delay_s"},
                                 "a delay between command and actuation", {{"delay_s"}}, 1};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index, double) const override {
    if (!(b.param("delay_s") >= 0.0)) throw std::invalid_argument("time_delay: need delay_s >= 0");
  }
  /// w[k - d] with d = delay / Ts possibly fractional (linear interpolation) and
  /// zero (rest) before the first sample.
  void actuate(const PhysicsBlock& b, double Ts, Eigen::Ref<Eigen::VectorXd> w) const override {
    const double delay_samples = b.param("delay_s") / Ts;
    if (!std::isfinite(delay_samples)) throw std::invalid_argument("time_delay: the delay is not a finite number");
    const Eigen::VectorXd original = w;
    // A delay beyond the record (either way) leaves nothing of it; clamping first
    // keeps the conversion to an index defined (a file may say delay_s 1e300).
    const double span = static_cast<double>(w.size()) + 1.0;
    const double clamped = std::clamp(delay_samples, -span, span);
    const auto whole = static_cast<Eigen::Index>(std::floor(clamped));
    const double frac = clamped - static_cast<double>(whole);
    auto at = [&](Eigen::Index k) { return k >= 0 && k < original.size() ? original[k] : 0.0; };
    for (Eigen::Index k = 0; k < w.size(); ++k) w[k] = (1.0 - frac) * at(k - whole) + frac * at(k - whole - 1);
  }
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    out.push_back(c.linearised(make_block("time_delay", j, i), "delay_s", 0.0, c.Ts(),
                               {"delay_s", 0.0, c.options().max_delay_samples * c.Ts()}, 1, "a delayed copy of the input"));
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "The response to " + s.input + " arrives " + format_number(b.param("delay_s") * 1e3, 3) +
           " ms later than the simulation predicts (a transport or computation delay).";
  }
};

}  // namespace

const PhysicsKind& time_delay_kind() {
  static const TimeDelay kind;
  return kind;
}

}  // namespace sysid
