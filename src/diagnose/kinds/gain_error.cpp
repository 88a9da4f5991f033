// gain_error: the measured output is a scaled copy of the simulated one (a
// sensor calibration or an actuator constant off).
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"

namespace sysid {

namespace {

class GainError final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    static const BlockKindInfo i{"gain_error", BlockStage::sensor, {"ratio"}, {"ratio"},
                                 "a gain error (measured / nominal)", {{"ratio", 1.0}}, 0};
    return i;
  }
  void sense(const PhysicsBlock& b, const SensorInputs&, Eigen::Ref<Eigen::MatrixXd> y) const override {
    y.col(b.output) *= b.param("ratio");
  }
  void propose(const DetectionContext& c, long, long i, std::vector<Candidate>& out) const override {
    out.push_back(c.linearised(make_block("gain_error", 0, i), "ratio", 1.0, 0.01, {"ratio", 0.5, 2.0, false}, 1,
                               "a scaled copy of the simulated output"));
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "The measured " + s.output + " is " + format_number(b.param("ratio"), 4) +
           " times the simulated one (a gain or calibration error).";
  }
};

}  // namespace

const PhysicsKind& gain_error_kind() {
  static const GainError kind;
  return kind;
}

}  // namespace sysid
