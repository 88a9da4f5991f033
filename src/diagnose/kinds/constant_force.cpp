// constant_force: a constant force inside the plant — gravity on a vertical
// axis, a cable's or a hose's pull, a preloaded spring far from its rest
// length. Not a sensor offset (offset_drift): the plant responds to it through
// its dynamics, and friction or a spring holds against it.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"

#include <algorithm>

namespace sysid {

namespace {

double constant_law(const double* p, double /*position*/, double /*velocity*/) { return p[0]; }

class ConstantForce final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    static const BlockKindInfo i{"constant_force", BlockStage::plant_feedback, {"force"}, {"force"},
                                 "a constant force inside the plant", {{"force"}}};
    return i;
  }
  bool reads_motion() const override { return false; }
  bool plant_force(const PhysicsBlock& b, PlantForce& f) const override {
    f = {b.input, b.output, constant_law, {b.param("force"), 0.0, 0.0, 0.0}};
    return true;
  }
  /// Linear in the force: one sensitivity, exact least squares. Not proposed on a
  /// nominal that carries an identified operating point (DetectionData): a
  /// constant force is there the same as that operating point shifted between
  /// records (a 0.06 % shift of an ARX nominal's input mean was "found" as a
  /// force on a record with 1e-4 noise).
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    if (c.data().identified_operating_point) return;
    const double u_max = c.data().u.col(j).cwiseAbs().maxCoeff();
    out.push_back(c.linearised(make_block("constant_force", j, i), "force", 0.0, 0.01 * u_max, {"force", -u_max, u_max},
                               c.simulator().substeps(), "a constant force on the plant"));
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "A constant force of " + format_number(b.param("force"), 3) + " (input units, positive along " + s.input +
           ") acts inside the plant at " + s.output + " (gravity on a vertical axis, a cable's pull).";
  }
};

}  // namespace

const PhysicsKind& constant_force_kind() {
  static const ConstantForce kind;
  return kind;
}

}  // namespace sysid
