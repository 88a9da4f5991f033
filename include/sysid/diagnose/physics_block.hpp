#pragma once
/// @file
/// Purpose: the vocabulary of physics that `sysid diagnose` can add to a nominal
/// model (DESIGN.md "diagnose: the report contract"): one PhysicsBlock per effect,
/// its named parameters, and where it acts.
///
/// Where each kind acts (the equations live in augmented_model.cpp):
/// - actuator (between the command u_j and the plant force):
///   deadzone, saturation, backlash, hysteresis (discrete Bouc-Wen), time_delay,
///   input_lag (first-order low-pass, part of the linear core). saturation is
///   either an amplifier clipping at +-limit (storage_pole = 0) or the overflow
///   above limit of a first-order store the input fills — a tank whose level the
///   nominal's pole storage_pole describes — part of whose spill (spill) reaches
///   the next stage (a store running dry is not modelled);
/// - inside the plant (a force fed back around the nominal model at input j,
///   computed from output i — collocated position — and its velocity):
///   coulomb_friction, cubic_stiffness; missing_mode is a modal term in parallel
///   with the nominal path from plant force j to output i;
/// - at the sensor (output i): gain_error, periodic_disturbance, offset_drift;
/// - cross_coupling: the nominal's direct path of input j (to output j) scaled
///   and added to output i.
///
/// Parameter names are those of DESIGN.md plus internal ones needed to simulate
/// (a mode's residue, a sine's phase, the Bouc-Wen shape, the linear part of a
/// cubic stiffness); `reported` lists the DESIGN.md ones. cubic_stiffness is the
/// force coefficient y^3 + linear_coefficient y: a nominal identified on data
/// from the nonlinear machine (a best linear approximation) already holds the
/// cubic term's average linear stiffness, 3 coefficient E[y^2] for a Gaussian y,
/// which the linear coefficient takes back out. Units: seconds, hertz, damping ratio; actuator and plant-force
/// effects in input units, sensor effects in output units.
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

/// Where in the signal chain a kind acts; fixes the simulation order.
enum class BlockStage { actuator, plant_feedback, plant_parallel, sensor, coupling };

/// Static description of a kind of physics.
struct BlockKindInfo {
  const char* kind;                      ///< DESIGN.md name, e.g. "cubic_stiffness"
  BlockStage stage;
  std::vector<const char*> parameters;   ///< every parameter the simulation reads, in a fixed order
  std::vector<const char*> reported;     ///< the DESIGN.md report parameters (a subset)
  const char* description;               ///< plain words, for summaries
};

/// The table of all kinds, in DESIGN.md order.
inline const std::vector<BlockKindInfo>& block_kinds() {
  static const std::vector<BlockKindInfo> kinds = {
      {"missing_mode", BlockStage::plant_parallel, {"freq_hz", "damping", "static_gain", "velocity_gain"},
       {"freq_hz", "damping"}, "a lightly damped mode the simulation lacks"},
      {"time_delay", BlockStage::actuator, {"delay_s"}, {"delay_s"}, "a delay between command and actuation"},
      {"gain_error", BlockStage::sensor, {"ratio"}, {"ratio"}, "a gain error (measured / nominal)"},
      {"input_lag", BlockStage::actuator, {"corner_hz"}, {"corner_hz"}, "a first-order lag in the actuator"},
      {"coulomb_friction", BlockStage::plant_feedback, {"level", "velocity_scale"}, {"level"},
       "Coulomb friction opposing the motion"},
      {"backlash", BlockStage::actuator, {"width"}, {"width"}, "play (backlash) in the actuation"},
      {"deadzone", BlockStage::actuator, {"width"}, {"width"}, "a dead zone in the actuation"},
      // storage_pole and spill were added after the first files were written:
      // optional in files (optional_parameter_default).
      {"saturation", BlockStage::actuator, {"limit", "storage_pole", "spill"}, {"limit"},
       "saturation of the actuation"},
      {"cubic_stiffness", BlockStage::plant_feedback, {"coefficient", "linear_coefficient"}, {"coefficient"},
       "a hardening (cubic) stiffness"},
      {"hysteresis", BlockStage::actuator, {"alpha", "beta", "gamma"}, {}, "hysteresis (Bouc-Wen) in the actuator"},
      {"periodic_disturbance", BlockStage::sensor, {"freq_hz", "amplitude", "phase_rad"}, {"freq_hz", "amplitude"},
       "a periodic disturbance not caused by the input"},
      {"offset_drift", BlockStage::sensor, {"offset", "slope"}, {"offset", "slope"}, "a sensor offset and drift"},
      {"cross_coupling", BlockStage::coupling, {"gain"}, {}, "coupling from another input the simulation lacks"},
      // Added after the 13 DESIGN.md kinds ("new kinds may be added"): a mode the
      // simulation has, at another frequency or damping in the recordings — the
      // first sign of a mass or stiffness error, e.g. in a finite-element model.
      // The nominal mode's contribution (numerator b1 s + b0 over its own
      // denominator, from the nominal's modal decomposition) is taken out and put
      // back with the new frequency and damping.
      {"mode_shift", BlockStage::plant_parallel,
       {"freq_hz", "damping", "nominal_freq_hz", "nominal_damping", "numerator_b0", "numerator_b1"},
       {"freq_hz", "damping", "nominal_freq_hz", "nominal_damping"},
       "a mode of the simulation at another frequency or damping"},
  };
  return kinds;
}

/// The table entry of `kind`; std::invalid_argument for an unknown kind.
inline const BlockKindInfo& block_kind_info(const std::string& kind) {
  for (const auto& k : block_kinds())
    if (kind == k.kind) return k;
  throw std::invalid_argument("unknown physics kind '" + kind + "'");
}

/// One effect added to the nominal model.
struct PhysicsBlock;

/// Parameters a model file may omit because they were added to a kind after
/// files with it were written, and their value then (keeping those files'
/// meaning): saturation's storage_pole = 0 (no store: an amplifier) and
/// spill = 0. False for any other parameter.
inline bool optional_parameter_default(const PhysicsBlock& block, const std::string& name, double& value);

struct PhysicsBlock {
  std::string kind;                      ///< a name from block_kinds()
  long input = 0;                        ///< the input channel it acts on (actuator, plant, coupling source)
  long output = 0;                       ///< the output channel it acts on (plant position, sensor, coupling target)
  std::map<std::string, double> params;  ///< every name of block_kind_info(kind).parameters

  /// The parameter's value; a parameter added to the kind later
  /// (optional_parameter_default) has its default when absent.
  double param(const std::string& name) const {
    const auto it = params.find(name);
    if (it != params.end()) return it->second;
    double fallback = 0.0;
    if (optional_parameter_default(*this, name, fallback)) return fallback;
    throw std::invalid_argument(kind + ": missing parameter '" + name + "'");
  }
  const BlockKindInfo& info() const { return block_kind_info(kind); }
};

inline bool optional_parameter_default(const PhysicsBlock& block, const std::string& name, double& value) {
  if (block.kind != "saturation") return false;
  if (name == "storage_pole" || name == "spill") {
    value = 0.0;
    return true;
  }
  return false;
}

}  // namespace sysid
