// The detectors of the physics hypotheses: each kind's in its own file
// (src/diagnose/kinds/); here, which channels each stage is proposed on. Method
// in include/sysid/diagnose/hypotheses.hpp.
#include "sysid/diagnose/hypotheses.hpp"

#include <algorithm>
#include <memory>

#include "diagnose/detail/detection_context.hpp"
#include "sysid/diagnose/physics_kind.hpp"

namespace sysid {

std::vector<Candidate> propose_candidates(const DetectionData& data, const DetectionOptions& options) {
  if (data.simulator == nullptr) throw std::invalid_argument("propose_candidates: need a simulator");
  if (data.u.rows() != data.y.rows() || data.current.rows() != data.y.rows() || data.current.cols() != data.y.cols())
    throw std::invalid_argument("propose_candidates: need u, y and current with the same rows (and y, current the same columns)");
  if (!(data.Ts > 0)) throw std::invalid_argument("propose_candidates: need Ts > 0");
  for (const AugmentedSimulator* r : data.plant_readings)
    if (r == nullptr || r->nominal().outputs() != data.y.cols())
      throw std::invalid_argument("propose_candidates: a plant reading's simulator is missing or has other outputs");
  const DetectionContext c(data, options);
  std::vector<std::unique_ptr<DetectionContext>> readings;
  for (const AugmentedSimulator* r : data.plant_readings) readings.push_back(std::make_unique<DetectionContext>(data, options, r));
  const long m = static_cast<long>(c.inputs()), l = static_cast<long>(c.outputs());
  std::vector<Candidate> out;
  for (const PhysicsKind* kind : physics_kinds()) {
    switch (kind->info().stage) {
      case BlockStage::sensor:
        for (long i = 0; i < l; ++i) kind->propose(c, 0, i, out);
        break;
      // A constant input (zero or not) carries no evidence about the actuator or
      // the plant's own forces: every such effect would be a constant too.
      case BlockStage::actuator:
        for (long j = 0; j < m; ++j)
          if (varies(c, j)) kind->propose(c, j, j < l ? j : 0, out);
        break;
      case BlockStage::plant_feedback:
        for (long j = 0; j < m; ++j)
          for (long i = 0; i < l; ++i) {
            if (!(l == 1 || i == j) || !varies(c, j)) continue;
            if (!kind->reads_motion() || readings.empty()) {
              kind->propose(c, j, i, out);
              continue;
            }
            for (const auto& reading : readings) {
              const std::size_t first = out.size();
              kind->propose(*reading, j, i, out);
              for (std::size_t k = first; k < out.size(); ++k) out[k].output_quantities = reading->simulator().output_quantities();
            }
          }
        break;
      case BlockStage::plant_parallel:
        for (long j = 0; j < m; ++j)
          for (long i = 0; i < l; ++i)
            if (m == 1 || l == 1 || i == j) kind->propose(c, j, i, out);
        break;
      case BlockStage::coupling:
        if (l < 2) break;
        for (long j = 0; j < std::min(m, l); ++j)
          for (long i = 0; i < l; ++i)
            if (i != j) kind->propose(c, j, i, out);
        break;
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Candidate& a, const Candidate& b) { return a.detector_score > b.detector_score; });
  return out;
}

}  // namespace sysid
