// The one list of physics kinds (physics_kind.hpp). Adding a kind: its file in
// this folder defining `const PhysicsKind& <name>_kind()`, and one line in
// SYSID_PHYSICS_KINDS below (DESIGN.md order, new kinds at the end).
#include "sysid/diagnose/physics_kind.hpp"

#include "sysid/diagnose/candidate_fit.hpp"
#include "sysid/diagnose/parameter_uncertainty.hpp"

#include <stdexcept>

#define SYSID_PHYSICS_KINDS(X)                                                                                        \
  X(missing_mode) X(time_delay) X(gain_error) X(input_lag) X(coulomb_friction) X(backlash) X(deadzone) X(saturation) \
  X(cubic_stiffness) X(hysteresis) X(periodic_disturbance) X(offset_drift) X(cross_coupling) X(mode_shift)           \
  X(constant_force)

namespace sysid {

#define SYSID_DECLARE_KIND(name) const PhysicsKind& name##_kind();
SYSID_PHYSICS_KINDS(SYSID_DECLARE_KIND)
#undef SYSID_DECLARE_KIND

const std::vector<const PhysicsKind*>& physics_kinds() {
#define SYSID_LIST_KIND(name) &name##_kind(),
  static const std::vector<const PhysicsKind*> kinds = {SYSID_PHYSICS_KINDS(SYSID_LIST_KIND)};
#undef SYSID_LIST_KIND
  return kinds;
}

const PhysicsKind& physics_kind(const std::string& kind) {
  for (const PhysicsKind* k : physics_kinds())
    if (kind == k->info().kind) return *k;
  throw std::invalid_argument("unknown physics kind '" + kind + "'");
}

const std::vector<BlockKindInfo>& block_kinds() {
  static const std::vector<BlockKindInfo> infos = [] {
    std::vector<BlockKindInfo> out;
    for (const PhysicsKind* k : physics_kinds()) out.push_back(k->info());
    return out;
  }();
  return infos;
}

const BlockKindInfo& block_kind_info(const std::string& kind) { return physics_kind(kind).info(); }

bool optional_parameter_default(const PhysicsBlock& block, const std::string& name, double& value) {
  return physics_kind(block.kind).optional_default(name, value);
}

std::map<std::string, double> PhysicsKind::reported(const PhysicsBlock& block) const {
  std::map<std::string, double> out;
  for (const char* name : info().reported) out[name] = block.param(name);
  return out;
}

std::map<std::string, double> PhysicsKind::reported_uncertainty(const Candidate& fitted, const CandidateUncertainty& u) const {
  std::map<std::string, double> out;
  for (const auto& [name, value] : reported(fitted.block)) {
    (void)value;
    const auto se = u.standard_errors.find(name);
    out[name] = se != u.standard_errors.end() ? se->second : 0.0;
  }
  return out;
}

}  // namespace sysid
