#pragma once
/// @file
/// Purpose: the warnings every identification gives about its data before
/// trusting a fit to it — inputs that carry the same signal
/// (input_collinearity.hpp), inputs not exciting enough for the model asked for
/// (persistent_excitation.hpp), output glitches a least-squares fit would follow
/// (isolated_spikes.hpp) — and about its result: an unstable model. One call each,
/// so every method reports the same things in the same words.
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "sysid/core/input_collinearity.hpp"
#include "sysid/core/io_data.hpp"
#include "sysid/core/isolated_spikes.hpp"
#include "sysid/core/persistent_excitation.hpp"
#include "sysid/core/state_space.hpp"

namespace sysid {

/// The data checks that do not depend on the model: inputs carrying the same
/// signal and isolated output spikes. A method may run them beside its
/// identification (they read `data` only) and hand them to
/// identification_data_warnings once the model is known.
struct ModelFreeDataWarnings {
  std::vector<std::string> collinear_inputs, spikes;
};

inline ModelFreeDataWarnings model_free_data_warnings(const IoData& data, const std::string& who) {
  return {collinear_input_warnings(data, who), isolated_spike_warnings(data, who)};
}

/// `required_excitation_order` is what the model needs of each input (see
/// persistent_excitation.hpp; 0: no input check), `model` names it in the message
/// ("ARX(4, 4)"), `who` prefixes every message ("arx"); `model_free` are the
/// checks above, already run on the same data.
inline std::vector<std::string> identification_data_warnings(const IoData& data, Eigen::Index required_excitation_order,
                                                             const std::string& model, const std::string& who,
                                                             ModelFreeDataWarnings model_free) {
  std::vector<std::string> out = std::move(model_free.collinear_inputs);
  for (auto& w : insufficient_excitation_warnings(data, required_excitation_order, model, who)) out.push_back(std::move(w));
  for (auto& w : model_free.spikes) out.push_back(std::move(w));
  return out;
}

/// The same, running every check here.
inline std::vector<std::string> identification_data_warnings(const IoData& data, Eigen::Index required_excitation_order,
                                                             const std::string& model, const std::string& who) {
  return identification_data_warnings(data, required_excitation_order, model, who, model_free_data_warnings(data, who));
}

/// A warning when the identified discrete model is unstable (spectral radius of A
/// >= 1): right for an unstable plant, whose simulation then grows without bound;
/// otherwise a sign of wrong orders or data. `hint` is appended (e.g. a method's
/// option that enforces stability). Empty when stable.
inline std::vector<std::string> unstable_model_warnings(const StateSpace& model, const std::string& who,
                                                        const std::string& hint = "") {
  if (model.A.rows() == 0 || model.Ts <= 0.0) return {};
  const double radius = model.A.eigenvalues().cwiseAbs().maxCoeff();
  if (!(radius >= 1.0)) return {};
  return {(who.empty() ? std::string() : who + ": ") + "the identified model is unstable (spectral radius " +
          std::to_string(radius) + "): right if the plant itself is unstable (its simulation then grows without " +
          "bound), otherwise a sign of wrong orders or bad data" + (hint.empty() ? std::string() : "; " + hint)};
}

}  // namespace sysid
