// Implementation of family/model_family.hpp (method in the header).
#include <sysid/family/model_family.hpp>
#include <sysid/core/assemble.hpp>
#include <sysid/core/format_number.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/parallel_for.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sysid {

namespace {

void check_members(const std::vector<FamilyMemberModel>& members) {
  if (members.empty()) throw std::invalid_argument("model family: need at least one member");
  const StateSpace& first = members.front().model;
  for (std::size_t i = 0; i < members.size(); ++i) {
    const StateSpace& m = members[i].model;
    if (!m.is_discrete()) throw std::invalid_argument("model family: member " + std::to_string(i) + " is not discrete");
    if (std::abs(m.Ts - first.Ts) > 1e-9 * first.Ts)
      throw std::invalid_argument("model family: member " + std::to_string(i) + " has Ts " + format_number(m.Ts, 6) +
                                  " s, member 0 has " + format_number(first.Ts, 6) + " s");
    if (m.inputs() != first.inputs() || m.outputs() != first.outputs())
      throw std::invalid_argument("model family: member " + std::to_string(i) + " has " + std::to_string(m.inputs()) +
                                  " inputs and " + std::to_string(m.outputs()) + " outputs, member 0 " +
                                  std::to_string(first.inputs()) + " and " + std::to_string(first.outputs()));
  }
}

}  // namespace

StateSpace family_member_model(const StateSpace& model, const Eigen::MatrixXd& K, const Eigen::MatrixXd& noise_covariance) {
  return model.inputs() > 0 ? model : disturbance_input_model(model, K, noise_covariance);
}

ModelFamilyResult analyse_model_family(const std::vector<FamilyMemberModel>& members, const ModelFamilyOptions& options) {
  check_members(members);
  ModelFamilyResult out;
  const double nyquist = 0.5 / members.front().model.Ts;
  if (options.band_hz) {
    out.band_lo_hz = options.band_hz->first;
    out.band_hi_hz = options.band_hz->second;
    out.band_source = "as given";
  } else {
    bool known = false;
    out.band_lo_hz = 0.0;
    out.band_hi_hz = nyquist;
    for (const FamilyMemberModel& m : members)
      if (m.error.band_hi_hz > m.error.band_lo_hz) {
        out.band_lo_hz = known ? std::max(out.band_lo_hz, m.error.band_lo_hz) : m.error.band_lo_hz;
        out.band_hi_hz = known ? std::min(out.band_hi_hz, m.error.band_hi_hz) : m.error.band_hi_hz;
        known = true;
      }
    out.band_source = known ? "the band every member's log excites (input power within 30 dB of its peak)"
                            : "no member's record with inputs at hand: up to Nyquist";
    if (!(out.band_hi_hz > out.band_lo_hz))
      throw std::invalid_argument("model family: the members' logs excite no common band; give --band");
  }
  if (!(out.band_hi_hz > out.band_lo_hz) || out.band_lo_hz < 0.0 || out.band_hi_hz > nyquist * (1.0 + 1e-12))
    throw std::invalid_argument("model family: the band " + format_number(out.band_lo_hz) + ".." + format_number(out.band_hi_hz) +
                                " Hz must satisfy 0 <= low < high <= Nyquist (" + format_number(nyquist) + " Hz)");
  out.band_hi_hz = std::min(out.band_hi_hz, nyquist * (1.0 - 1e-9));

  std::vector<std::vector<ModeEstimate>> member_modes;
  for (const FamilyMemberModel& m : members)
    member_modes.push_back(trackable_modes(m.model, out.band_lo_hz, out.band_hi_hz, options.max_mode_damping));
  out.modes = track_modes(member_modes, options.tracking);
  out.frequency_hz = family_frequency_grid(out.band_lo_hz, out.band_hi_hz, member_modes, options.grid_points);

  if (members.size() < 2) {
    out.warnings.push_back("one member only: no spread, so no uncertainty bound or weight");
    return out;
  }
  std::vector<std::vector<Eigen::MatrixXcd>> frf(members.size());
  std::vector<Eigen::VectorXd> sd(members.size());
  parallel_for(members.size(), [&](std::size_t i) {
    frf[i] = frequency_response(members[i].model, out.frequency_hz);
    sd[i] = members[i].error.at(out.frequency_hz);
  });
  out.bound = uncertainty_bound(frf, sd, options.bound);
  if (!out.bound->with_allowance)
    out.warnings.push_back("some members came without their logs: the bound has no allowance for estimation error");
  if (!(out.bound->bound.maxCoeff() > 0.0)) {
    out.warnings.push_back("the members do not differ from the nominal: no weight");
    return out;
  }
  UncertaintyWeightOptions wo;
  wo.order = options.weight_order;
  out.weight = fit_uncertainty_weight(out.frequency_hz, out.bound->bound, members.front().model.Ts, wo);
  for (const std::string& w : out.weight->warnings) out.warnings.push_back("weight: " + w);
  return out;
}

}  // namespace sysid
