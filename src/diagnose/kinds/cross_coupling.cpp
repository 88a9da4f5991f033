// cross_coupling: the motion input j causes at output j, seen at output i
// (a coupling the simulation lacks): the nominal's direct path of input j,
// scaled and added to output i.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"
#include "sysid/core/simulate.hpp"

namespace sysid {

namespace {

class CrossCoupling final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    static const BlockKindInfo i{"cross_coupling", BlockStage::coupling, {"gain"}, {},
                                 "coupling from another input the simulation lacks", {{"gain"}}, 1};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index outputs, double) const override {
    if (b.input >= outputs)
      throw std::invalid_argument("cross_coupling: the source input " + std::to_string(b.input) +
                                  " has no direct output to copy (model has " + std::to_string(outputs) + " outputs)");
  }
  void sense(const PhysicsBlock& b, const SensorInputs& in, Eigen::Ref<Eigen::MatrixXd> y) const override {
    const StateSpace& nom = in.nominal;
    StateSpace direct(nom.A, nom.B.col(b.input), nom.C.row(b.input), nom.D.block(b.input, b.input, 1, 1), nom.Ts);
    y.col(b.output) += b.param("gain") * sysid::simulate(direct, in.drive.col(b.input)).col(0);
  }
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    out.push_back(c.linearised(make_block("cross_coupling", j, i), "gain", 0.0, 0.01, {"gain", -2.0, 2.0}, 1,
                               "input " + std::to_string(j + 1) + "'s motion seen at output " + std::to_string(i + 1)));
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "Input " + s.input + " moves output " + s.output + " (coupling gain " + format_number(b.param("gain"), 3) +
           ") where the simulation has no coupling.";
  }
};

}  // namespace

const PhysicsKind& cross_coupling_kind() {
  static const CrossCoupling kind;
  return kind;
}

}  // namespace sysid
