// missing_mode: a lightly damped mode the simulation lacks, in parallel with
// the nominal path from the plant force to the output.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"
#include "sysid/core/math_constants.hpp"

#include <algorithm>
#include <cmath>

namespace sysid {

namespace {

class MissingMode final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    // The defining parameters are the residue's two gains: a mode with neither is absent.
    static const BlockKindInfo i{"missing_mode", BlockStage::plant_parallel,
                                 {"freq_hz", "damping", "static_gain", "velocity_gain"}, {"freq_hz", "damping"},
                                 "a lightly damped mode the simulation lacks", {{"static_gain"}, {"velocity_gain"}}};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index, double Ts) const override {
    if (!(b.param("freq_hz") > 0.0 && b.param("freq_hz") < 0.5 / Ts))
      throw std::invalid_argument("missing_mode: need freq_hz in (0, Nyquist)");
    if (!(b.param("damping") > 0.0)) throw std::invalid_argument("missing_mode: need damping > 0");
  }
  std::vector<ParallelMode> parallel_modes(const PhysicsBlock& b) const override {
    return {{b.input, b.output, b.param("freq_hz"), b.param("damping"), b.param("static_gain"), b.param("velocity_gain")}};
  }

  /// Grid in frequency (around each significant model-error band) and damping;
  /// at each point the two residue gains enter linearly and are solved by least squares.
  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    for (double f0 : c.data().mode_frequencies_hz) {
      Candidate best;
      best.detector_score = -1;
      const double f_max = 0.49 / c.Ts();  // a mode must stay below Nyquist
      for (double scale : {0.97, 0.985, 1.0, 1.015, 1.03}) {
        if (f0 * scale >= f_max) continue;
        for (double zeta : {0.005, 0.02, 0.06}) {
          PhysicsBlock b = make_block("missing_mode", j, i);
          b.params["freq_hz"] = f0 * scale;
          b.params["damping"] = zeta;
          const auto [coef, explained] = c.regress(c.sensitivities(b, {{"static_gain", 1.0}, {"velocity_gain", 1.0}}));
          if (explained > best.detector_score) {
            b.params["static_gain"] = coef[0];
            b.params["velocity_gain"] = coef[1];
            best.block = b;
            best.detector_score = explained;
          }
        }
      }
      if (best.detector_score < 0) continue;  // every grid point beyond Nyquist
      const double f = best.block.param("freq_hz");
      const double gs = best.block.param("static_gain"), gv = best.block.param("velocity_gain");
      const double reach = 4.0 * std::max(std::abs(gs), std::abs(gv)) + kTinyScale;
      best.free = {{"freq_hz", 0.85 * f, std::min(1.15 * f, f_max), true},
                   {"damping", 0.001, 0.2, true},
                   {"static_gain", -reach, reach},
                   {"velocity_gain", -reach, reach}};
      best.detector_score = std::max(0.0, best.detector_score);
      best.evidence = "the model-error FRF is significant near " + format_number(f0, 5) + " Hz; a mode there explains " +
                      percent(best.detector_score);
      out.push_back(best);
    }
  }

  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "The recordings contain a lightly damped mode at " + format_number(b.param("freq_hz"), 4) + " Hz (damping " +
           format_number(b.param("damping"), 2) + ") in the path " + s.input + " -> " + s.output + " that the simulation lacks.";
  }
};

}  // namespace

const PhysicsKind& missing_mode_kind() {
  static const MissingMode kind;
  return kind;
}

}  // namespace sysid
