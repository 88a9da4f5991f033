// mode_shift: a mode the simulation has, at another frequency or damping in the
// recordings — the first sign of a mass or stiffness error, e.g. in a
// finite-element model. The nominal mode's contribution (numerator b1 s + b0
// over its own denominator, from the nominal's modal decomposition) is taken out
// and put back with the new frequency and damping.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"
#include "sysid/core/math_constants.hpp"

#include <algorithm>
#include <cmath>

namespace sysid {

namespace {

/// One lightly damped mode of the nominal in the path input j -> output i:
/// b1 s + b0 over s^2 + 2 zeta w s + w^2.
struct NominalMode {
  double freq_hz = 0.0, damping = 0.0, b0 = 0.0, b1 = 0.0;
};

/// The nominal's lightly damped modes (damping < 0.3, below 0.45 fs) with their
/// numerators in the path j -> i, from the eigen-decomposition of its continuous
/// equivalent: a pole pair p, conj(p) with residue r = (C v)_i (w^T B)_j contributes
/// (2 Re(r) s - 2 Re(r conj(p))) / (s^2 - 2 Re(p) s + |p|^2).
std::vector<NominalMode> nominal_modes(const DetectionContext& c, long j, long i) {
  std::vector<NominalMode> modes;
  const ModalBasis& basis = c.nominal_basis();
  for (Eigen::Index k = 0; k < basis.poles.size(); ++k) {
    const std::complex<double> p = basis.poles(k);
    if (!(p.imag() > 0.0)) continue;
    const double w = std::abs(p), zeta = -p.real() / w, f = w / kTwoPi;
    if (!(zeta > 0.0 && zeta < 0.3) || f >= 0.45 / c.Ts()) continue;
    const std::complex<double> r = basis.output_shapes(i, k) * basis.input_shapes(k, j);
    modes.push_back({f, zeta, -2.0 * (r * std::conj(p)).real(), 2.0 * r.real()});
  }
  return modes;
}

class ModeShift final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    // Added after the 13 DESIGN.md kinds ("new kinds may be added"). Absent when
    // the mode is where the nominal has it: frequency and damping both nominal.
    static const BlockKindInfo i{"mode_shift", BlockStage::plant_parallel,
                                 {"freq_hz", "damping", "nominal_freq_hz", "nominal_damping", "numerator_b0", "numerator_b1"},
                                 {"freq_hz", "damping", "nominal_freq_hz", "nominal_damping"},
                                 "a mode of the simulation at another frequency or damping",
                                 {{"freq_hz", 0.0, "nominal_freq_hz"}, {"damping", 0.0, "nominal_damping"}}};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index, double Ts) const override {
    auto need = [&](bool ok, const char* what) {
      if (!ok) throw std::invalid_argument(std::string("mode_shift: need ") + what);
    };
    need(b.param("freq_hz") > 0.0 && b.param("freq_hz") < 0.5 / Ts, "freq_hz in (0, Nyquist)");
    need(b.param("damping") > 0.0, "damping > 0");
    need(b.param("nominal_freq_hz") > 0.0 && b.param("nominal_freq_hz") < 0.5 / Ts, "nominal_freq_hz in (0, Nyquist)");
    need(b.param("nominal_damping") > 0.0, "nominal_damping > 0");
  }
  /// The nominal mode (numerator b1 s + b0) out, the same numerator over the
  /// moved denominator in: static_gain = b0 / w^2, velocity_gain = b1 / w.
  std::vector<ParallelMode> parallel_modes(const PhysicsBlock& b) const override {
    const double b0 = b.param("numerator_b0"), b1 = b.param("numerator_b1");
    const double w_old = kTwoPi * b.param("nominal_freq_hz"), w_new = kTwoPi * b.param("freq_hz");
    return {{b.input, b.output, b.param("nominal_freq_hz"), b.param("nominal_damping"), -b0 / (w_old * w_old), -b1 / w_old},
            {b.input, b.output, b.param("freq_hz"), b.param("damping"), b0 / (w_new * w_new), b1 / w_new}};
  }

  /// Each nominal mode moved in frequency on a small grid (damping kept), then in
  /// damping at the best frequency; scored by the residual energy the moved mode
  /// explains as it is (a shift is not linear in the frequency beyond a fraction
  /// of the half-power bandwidth, so no linearised score).
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    const double f_max = 0.49 / c.Ts();
    for (const NominalMode& mode : nominal_modes(c, j, i)) {
      PhysicsBlock b = make_block("mode_shift", j, i);
      b.params["nominal_freq_hz"] = mode.freq_hz;
      b.params["nominal_damping"] = mode.damping;
      b.params["numerator_b0"] = mode.b0;
      b.params["numerator_b1"] = mode.b1;
      b.params["damping"] = mode.damping;
      double best_score = -1.0, best_f = mode.freq_hz, best_zeta = mode.damping;
      for (double scale : {0.97, 0.985, 0.993, 0.997, 1.003, 1.007, 1.015, 1.03}) {
        if (mode.freq_hz * scale >= f_max) continue;
        b.params["freq_hz"] = mode.freq_hz * scale;
        const double score = c.explained_as_is(c.effect(b));
        if (score > best_score) best_score = score, best_f = mode.freq_hz * scale;
      }
      if (best_score < 0.0) continue;
      b.params["freq_hz"] = best_f;
      for (double factor : {0.6, 1.6}) {
        b.params["damping"] = mode.damping * factor;
        const double score = c.explained_as_is(c.effect(b));
        if (score > best_score) best_score = score, best_zeta = mode.damping * factor;
      }
      b.params["damping"] = best_zeta;
      Candidate candidate;
      candidate.block = b;
      candidate.free = {{"freq_hz", 0.9 * mode.freq_hz, std::min(1.1 * mode.freq_hz, f_max), true},
                        {"damping", 0.2 * mode.damping, std::min(5.0 * mode.damping, 0.6), true}};
      candidate.detector_score = std::max(0.0, best_score);
      candidate.evidence = "the simulation's mode at " + format_number(mode.freq_hz) + " Hz moved to " +
                           format_number(best_f) + " Hz explains " + percent(candidate.detector_score);
      out.push_back(candidate);
    }
  }

  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    // (f / f0)^2 - 1 is the modal stiffness-to-mass ratio error the shift implies.
    const double ratio = b.param("freq_hz") / b.param("nominal_freq_hz");
    return "The simulation's mode at " + format_number(b.param("nominal_freq_hz"), 4) + " Hz (damping " +
           format_number(b.param("nominal_damping"), 2) + ") is at " + format_number(b.param("freq_hz"), 4) + " Hz (damping " +
           format_number(b.param("damping"), 2) + ") in the path " + s.input + " -> " + s.output +
           ": its modal stiffness-to-mass ratio is " + format_number(100.0 * (ratio * ratio - 1.0), 2) +
           " % off (a mass or stiffness error of the model).";
  }
};

}  // namespace

const PhysicsKind& mode_shift_kind() {
  static const ModeShift kind;
  return kind;
}

}  // namespace sysid
