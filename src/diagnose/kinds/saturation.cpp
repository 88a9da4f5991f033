// saturation: an amplifier clipping at +-limit, or the overflow of a first-order
// store the input fills (a tank, a pneumatic chamber) above a level.
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"

#include <algorithm>
#include <cmath>

namespace sysid {

namespace {

/// An amplifier clipping at +-limit (storage_pole a = 0), or the overflow of a
/// first-order store the input fills (a tank; 0 < a < 1). The store's level, in
/// input units (unit DC gain),
///   v[k+1] = min(a v[k] + (1 - a) w[k], limit),
/// and what flows on to the plant is the level the next stage sees,
///   z[k+1] = v[k+1] + spill * overflow[k] / (1 - a),
/// overflow = the part of a v + (1 - a) w above the limit, of which the fraction
/// `spill` reaches the next stage at once (1 / (1 - a) turns an overflowing
/// volume into the level that would carry it out in one step; the rest is lost).
/// The nominal holds the store's own dynamics (its pole a, e.g. the upper tank
/// of cascaded tanks), so the block hands it the input that makes that pole
/// reproduce z exactly: w_out[k] = (z[k+1] - a z[k]) / (1 - a), causal because
/// z[k+1] depends on w[k] only; below the limit w_out = w. Physics: the overflow
/// of the upper tank in M. Schoukens, P. Mattsson, T. Wigren and J.P. Noel,
/// "Cascaded tanks benchmark combining soft and hard nonlinearities", 2016 (part
/// of the spill falls into the lower tank). The store starts filled to its first
/// input; it never runs dry (no lower limit).
void apply_saturation(double limit, double a, double spill, Eigen::Ref<Eigen::VectorXd> w) {
  if (a == 0.0) {
    w = w.cwiseMax(-limit).cwiseMin(limit);
    return;
  }
  if (w.size() == 0) return;
  double level = std::min(w[0], limit), seen = level;
  for (Eigen::Index k = 0; k < w.size(); ++k) {
    const double filled = a * level + (1.0 - a) * w[k];
    const double next_level = std::min(filled, limit);
    const double next_seen = next_level + spill * (filled - next_level) / (1.0 - a);
    w[k] = (next_seen - a * seen) / (1.0 - a);
    level = next_level;
    seen = next_seen;
  }
}

/// The nominal's real discrete poles in (0, 1), slowest first: the first-order
/// stores (tanks, thermal masses) an input could fill.
std::vector<double> store_poles(const DetectionContext& c) {
  std::vector<double> poles;
  Eigen::EigenSolver<Eigen::MatrixXd> eig(c.simulator().nominal().A, false);
  if (eig.info() != Eigen::Success) return poles;
  for (Eigen::Index k = 0; k < eig.eigenvalues().size(); ++k) {
    const std::complex<double> p = eig.eigenvalues()(k);
    if (std::abs(p.imag()) <= 1e-12 * std::abs(p) && p.real() > 0.0 && p.real() < 1.0) poles.push_back(p.real());
  }
  std::sort(poles.begin(), poles.end(), std::greater<>());
  return poles;
}

/// Lowest and highest level of a first-order store (pole a, unit DC gain) filled
/// by u from equilibrium with its first sample, without overflow.
std::pair<double, double> store_level_range(const Eigen::VectorXd& u, double a) {
  double level = u[0], low = level, high = level;
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    level = a * level + (1.0 - a) * u[k];
    low = std::min(low, level);
    high = std::max(high, level);
  }
  return {low, high};
}

class Saturation final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    // storage_pole and spill were added after the first files were written:
    // optional in files (optional_default). No defining parameter: a clipping
    // level is "absent" only beyond the largest input, which the acceptance test
    // of the fit already judges.
    static const BlockKindInfo i{"saturation", BlockStage::actuator, {"limit", "storage_pole", "spill"}, {"limit"},
                                 "saturation of the actuation", {}, 0};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index, double) const override {
    auto need = [](bool ok, const char* what) {
      if (!ok) throw std::invalid_argument(std::string("saturation: need ") + what);
    };
    need(b.param("limit") > 0.0 || b.param("storage_pole") > 0.0, "limit > 0 (an amplifier's +-limit)");
    need(b.param("storage_pole") >= 0.0 && b.param("storage_pole") < 1.0, "storage_pole in [0, 1)");
    need(b.param("spill") >= 0.0 && b.param("spill") <= 1.0, "spill in [0, 1]");
  }
  bool optional_default(const std::string& name, double& value) const override {
    if (name != "storage_pole" && name != "spill") return false;
    value = 0.0;  // no store: an amplifier; nothing spills on
    return true;
  }
  void actuate(const PhysicsBlock& b, double, Eigen::Ref<Eigen::VectorXd> w) const override {
    apply_saturation(b.param("limit"), b.param("storage_pole"), b.param("spill"), w);
  }

  void propose(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) const override {
    const Eigen::VectorXd uj = c.data().u.col(j);
    const double u_max = uj.cwiseAbs().maxCoeff();
    // Saturation is not smooth where it vanishes (limit = max |u|): grid of limits.
    std::vector<PhysicsBlock> grid;
    for (double q : {0.995, 0.98, 0.95, 0.9, 0.85, 0.8, 0.7}) {
      PhysicsBlock b = make_block("saturation", j, i);
      b.params["limit"] = q * u_max;
      grid.push_back(b);
    }
    Candidate best = c.best_as_is(grid);
    best.free = {{"limit", 0.3 * u_max, u_max}};
    best.detector_score = std::max(0.0, best.detector_score);
    best.evidence = "clipping the largest inputs explains " + percent(best.detector_score);
    out.push_back(best);
    propose_store_overflow(c, j, i, out);
  }

  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    if (b.param("storage_pole") > 0.0) {
      // Time constant of the store from its discrete pole: a = exp(-Ts / tau).
      return "The store that " + s.input + " fills (a tank, chamber or reservoir with a time constant of " +
             format_number(-s.Ts / std::log(b.param("storage_pole")), 3) + " s) overflows above the level a steady " + s.input +
             " of " + format_number(b.param("limit"), 4) + " (input units, from the operating point) would reach; " +
             format_number(100.0 * b.param("spill"), 3) + " % of the spill flows on to the next stage.";
    }
    return "The actuation of " + s.input + " saturates at +-" + format_number(b.param("limit"), 4) + " (input units).";
  }

 private:
  /// The input fills a first-order store with one of the nominal's real poles,
  /// which overflows above a level. Grid over the pole (the four slowest), the
  /// level (fractions of the store's range) and the spill.
  static void propose_store_overflow(const DetectionContext& c, long j, long i, std::vector<Candidate>& out) {
    std::vector<double> poles = store_poles(c);
    if (poles.empty()) return;
    if (poles.size() > 4) poles.resize(4);
    const Eigen::VectorXd uj = c.data().u.col(j);
    std::vector<PhysicsBlock> grid;
    for (double a : poles) {
      const auto [low, high] = store_level_range(uj, a);
      for (double q : {0.95, 0.85, 0.75, 0.6, 0.45})
        for (double spill : {0.0, 0.5}) {
          PhysicsBlock b = make_block("saturation", j, i);
          b.params["limit"] = low + q * (high - low);
          b.params["storage_pole"] = a;
          b.params["spill"] = spill;
          grid.push_back(b);
        }
    }
    Candidate best = c.best_as_is(grid);
    const double a = best.block.param("storage_pole");
    const auto [low, high] = store_level_range(uj, a);
    // The pole may move by a factor of two in time constant: a nominal fitted to
    // the saturating store holds a compromise of its dynamics.
    best.free = {{"limit", low + 0.3 * (high - low), high}, {"storage_pole", a * a, std::sqrt(a)}, {"spill", 0.0, 1.0}};
    best.detector_score = std::max(0.0, best.detector_score);
    best.evidence = "a store filled by the input (pole " + format_number(a, 6) + ") overflowing above " +
                    format_number(best.block.param("limit"), 6) + " explains " + percent(best.detector_score);
    out.push_back(best);
  }
};

}  // namespace

const PhysicsKind& saturation_kind() {
  static const Saturation kind;
  return kind;
}

}  // namespace sysid
