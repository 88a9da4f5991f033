// offset_drift: a sensor offset and a linear drift, offset + slope t.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"

#include <algorithm>

namespace sysid {

namespace {

class OffsetDrift final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    static const BlockKindInfo i{"offset_drift", BlockStage::sensor, {"offset", "slope"}, {"offset", "slope"},
                                 "a sensor offset and drift", {{"offset"}, {"slope"}}, 2};
    return i;
  }
  void sense(const PhysicsBlock& b, const SensorInputs& in, Eigen::Ref<Eigen::MatrixXd> y) const override {
    y.col(b.output).array() += b.param("offset") + b.param("slope") * in.time_s.array();
  }
  /// Offset and drift are linear: two regressors, exact least squares.
  void propose(const DetectionContext& c, long, long i, std::vector<Candidate>& out) const override {
    const Eigen::VectorXd yi = c.data().y.col(i);
    const double y_rms = rms(yi.array() - yi.mean());
    PhysicsBlock b = make_block("offset_drift", 0, i);
    const auto [coef, explained] = c.regress(c.sensitivities(b, {{"offset", 1.0}, {"slope", 1.0}}));
    const double T = c.duration();
    b.params["offset"] = std::clamp(coef[0], -3 * y_rms, 3 * y_rms);
    b.params["slope"] = std::clamp(coef[1], -3 * y_rms / T, 3 * y_rms / T);
    out.push_back({b, {{"offset", -3 * y_rms, 3 * y_rms}, {"slope", -3 * y_rms / T, 3 * y_rms / T}}, 1,
                   std::max(0.0, explained),
                   "a constant and a ramp explain " + percent(std::max(0.0, explained)) + " of the residual energy"});
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "The sensor " + s.output + " has an offset of " + format_number(b.param("offset"), 3) + " and a drift of " +
           format_number(b.param("slope"), 3) + " per second (output units).";
  }
};

}  // namespace

const PhysicsKind& offset_drift_kind() {
  static const OffsetDrift kind;
  return kind;
}

}  // namespace sysid
