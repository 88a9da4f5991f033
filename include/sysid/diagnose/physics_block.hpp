#pragma once
/// @file
/// Purpose: the vocabulary of physics that `sysid diagnose` can add to a nominal
/// model (DESIGN.md "diagnose: the report contract"): one PhysicsBlock per effect,
/// its named parameters, and where it acts.
///
/// Where each kind acts (each kind's equations live in its own file,
/// src/diagnose/kinds/<kind>.cpp, behind physics_kind.hpp):
/// - actuator (between the command u_j and the plant force):
///   deadzone, saturation, backlash, hysteresis (discrete Bouc-Wen), time_delay,
///   input_lag (first-order low-pass, part of the linear core). saturation is
///   either an amplifier clipping at +-limit (storage_pole = 0) or the overflow
///   above limit of a first-order store the input fills — a tank whose level the
///   nominal's pole storage_pole describes — part of whose spill (spill) reaches
///   the next stage (a store running dry is not modelled);
/// - inside the plant (a force added to the drive at input j, computed from the
///   motion at output i — collocated — read as the output's quantity says:
///   OutputQuantity in augmented_model.hpp): coulomb_friction (optionally
///   direction-dependent: asymmetry r in [-1, 1], levels level (1 +- r)), cubic_stiffness, constant_force; missing_mode and
///   mode_shift are modal terms in parallel with the nominal path from plant
///   force j to output i;
/// - at the sensor (output i): gain_error, periodic_disturbance, offset_drift;
/// - cross_coupling: the nominal's direct path of input j (to output j) scaled
///   and added to output i.
///
/// Parameter names are those of DESIGN.md plus internal ones needed to simulate
/// (a mode's residue, a sine's phase, the Bouc-Wen shape, the linear part of a
/// cubic stiffness); `reported` lists the DESIGN.md ones. cubic_stiffness is the
/// force coefficient p^3 + linear_coefficient p (p the position): a nominal
/// identified on data from the nonlinear machine (a best linear approximation)
/// already holds the cubic term's average linear stiffness, 3 coefficient E[p^2]
/// for a Gaussian p, which the linear coefficient takes back out. Units: seconds,
/// hertz, damping ratio; actuator and plant-force effects in input units, sensor
/// effects in output units.
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

/// Where in the signal chain a kind acts; fixes the simulation order.
enum class BlockStage { actuator, plant_feedback, plant_parallel, sensor, coupling };

/// A parameter whose value says whether the effect is there at all, and its value
/// when it is not (zero friction, unit gain, the nominal's own frequency). A
/// finding is reported under its kind's name only when at least one defining
/// parameter differs from its null value by more than its uncertainty allows
/// (DESIGN.md "diagnose"). The null value is `null_value`, or the block's own
/// value of `null_parameter` when that is set (a moved mode's nominal
/// frequency). `reciprocal`: the effect vanishes as the parameter grows without
/// bound (a lag's corner), so 1/value is tested against 0.
struct DefiningParameter {
  const char* name;
  double null_value = 0.0;
  const char* null_parameter = nullptr;
  bool reciprocal = false;
};

/// Static description of a kind of physics.
struct BlockKindInfo {
  const char* kind;                      ///< DESIGN.md name, e.g. "cubic_stiffness"
  BlockStage stage;
  std::vector<const char*> parameters;   ///< every parameter the simulation reads, in a fixed order
  std::vector<const char*> reported;     ///< the DESIGN.md report parameters (a subset)
  const char* description;               ///< plain words, for summaries
  std::vector<DefiningParameter> defining;  ///< empty: no single parameter says "absent" (a clipping level)
  int chain_order = 0;                   ///< order within the actuator and sensor stages (lower first)
  /// Parameters that refine the kind (a friction's difference between the two
  /// directions): each is held at its null value, and the finding reported
  /// without it, unless the data show it differs from that by more than its
  /// uncertainty allows.
  std::vector<DefiningParameter> optional_terms = {};
};

/// Every kind's description, in DESIGN.md order (served by the kinds' registry,
/// physics_kind.hpp).
const std::vector<BlockKindInfo>& block_kinds();

/// The description of `kind`; std::invalid_argument for an unknown kind.
const BlockKindInfo& block_kind_info(const std::string& kind);

struct PhysicsBlock;

/// Parameters a model file may omit because they were added to a kind after
/// files with it were written, and their value then (keeping those files'
/// meaning), e.g. saturation's storage_pole = 0 (no store: an amplifier). False
/// for any other parameter.
bool optional_parameter_default(const PhysicsBlock& block, const std::string& name, double& value);

/// One effect added to the nominal model.
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

}  // namespace sysid
