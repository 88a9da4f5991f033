// periodic_disturbance: a sine in the output that the input does not cause
// (mains hum, a fan, a pump), amplitude sin(2 pi f t + phase).
#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"
#include "sysid/core/math_constants.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sysid {

namespace {

class PeriodicDisturbance final : public PhysicsKind {
 public:
  const BlockKindInfo& info() const override {
    static const BlockKindInfo i{"periodic_disturbance", BlockStage::sensor, {"freq_hz", "amplitude", "phase_rad"},
                                 {"freq_hz", "amplitude"}, "a periodic disturbance not caused by the input", {{"amplitude"}}, 3};
    return i;
  }
  void check(const PhysicsBlock& b, Eigen::Index, Eigen::Index, double) const override {
    if (!(b.param("freq_hz") > 0.0)) throw std::invalid_argument("periodic_disturbance: need freq_hz > 0");
  }
  void sense(const PhysicsBlock& b, const SensorInputs& in, Eigen::Ref<Eigen::MatrixXd> y) const override {
    y.col(b.output).array() += b.param("amplitude") * (kTwoPi * b.param("freq_hz") * in.time_s.array() + b.param("phase_rad")).sin();
  }
  /// For each residual peak not coherent with an input: zoom around it (the cost
  /// of a sine in frequency is as narrow as 1/T, far finer than the spectral
  /// bins, so scan at 0.05/T) and fit the sine's two quadratures by least squares.
  void propose(const DetectionContext& c, long, long i, std::vector<Candidate>& out) const override {
    for (double f0 : c.data().peak_frequencies_hz) {
      const double T = c.duration(), df = std::max(c.data().frequency_resolution_hz, 1.0 / T);
      const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(c.rows(), 0.0, static_cast<double>(c.rows() - 1) * c.Ts());
      const Eigen::VectorXd r = c.residual().col(i);
      double best_f = f0, best_power = -1, best_a = 0, best_b = 0;
      for (double f = std::max(f0 - 1.5 * df, 0.5 / T); f <= f0 + 1.5 * df; f += 0.05 / T) {
        Eigen::MatrixXd G(c.rows(), 2);
        G.col(0) = (kTwoPi * f * t.array()).sin();
        G.col(1) = (kTwoPi * f * t.array()).cos();
        const Eigen::Vector2d ab = (G.transpose() * G).ldlt().solve(G.transpose() * r);  // 2x2, well conditioned
        const double power = (G * ab).squaredNorm();
        if (power > best_power) best_power = power, best_f = f, best_a = ab[0], best_b = ab[1];
      }
      PhysicsBlock b = make_block("periodic_disturbance", 0, i);
      const double amplitude = std::hypot(best_a, best_b), phase = std::atan2(best_b, best_a);
      b.params["freq_hz"] = best_f;
      b.params["amplitude"] = amplitude;
      b.params["phase_rad"] = phase;
      const double explained = std::max(0.0, c.explained_as_is(c.effect(b)));
      out.push_back({b,
                     {{"freq_hz", best_f - 0.5 / T, best_f + 0.5 / T},
                      {"amplitude", 0.0, 3.0 * amplitude + kTinyScale},
                      {"phase_rad", phase - std::numbers::pi, phase + std::numbers::pi}},
                     1, explained, "a residual peak not coherent with the input; a sine explains " + percent(explained)});
    }
  }
  std::string summary(const PhysicsBlock& b, const SummaryContext& s) const override {
    return "A periodic disturbance at " + format_number(b.param("freq_hz"), 5) + " Hz with amplitude " +
           format_number(b.param("amplitude"), 3) + " (output units) is present in " + s.output + " and is not caused by the input.";
  }
};

}  // namespace

const PhysicsKind& periodic_disturbance_kind() {
  static const PeriodicDisturbance kind;
  return kind;
}

}  // namespace sysid
