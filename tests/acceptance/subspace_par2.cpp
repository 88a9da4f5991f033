// Acceptance of the foundation issue on the Par2 piezo log (data/generate_examples.cpp):
// N4SID, MOESP and CVA at order 10 recover every mode inside the excited band
// (natural frequency within 0.5 %, damping ratio within 10 %), and reach an
// in-band validation fit within 1 point of the true model's; --order auto picks 10.
#include <sysid/core/modal_table.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/sos_filter.hpp>
#include <sysid/subspace/n4sid.hpp>
#include <sysid/validate/fit.hpp>

#include <gtest/gtest.h>

using namespace sysid;

namespace {

const std::string kData = SYSID_TEST_DATA_DIR;

IoData load(const std::string& name) {
  LogOptions o;
  o.inputs = {"u"};
  o.outputs = {"y"};
  return read_log(kData + "/" + name, o);
}

/// In-band fit: measured and simulated outputs through the same zero-phase
/// 5th-order Butterworth low-pass at 1.2 x the excited band (120 Hz).
double in_band_fit(const StateSpace& g, const Eigen::VectorXd& u_offset, const Eigen::VectorXd& y_offset, const IoData& val) {
  const Experiment& e = val.experiments.front();
  const Eigen::MatrixXd u = e.u.rowwise() - u_offset.transpose();
  const Eigen::MatrixXd y_hat = simulate(g, u).rowwise() + y_offset.transpose();
  const SecondOrderSections lp = butterworth(5, BandType::lowpass, 120.0, 0.0, 1.0 / val.Ts);
  return fit_percent(filtfilt(lp, e.y), filtfilt(lp, y_hat))(0);
}

struct Reference {
  StateSpace truth;
  IoData estimation, validation;
  double true_fit;
};

const Reference& reference() {
  static const Reference r = [] {
    Reference ref{read_model_json(kData + "/par2_gu_true.json").model, load("par2_gu.csv"), load("par2_gu_val.csv"), 0.0};
    ref.true_fit = in_band_fit(ref.truth, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), ref.validation);
    return ref;
  }();
  return r;
}

}  // namespace

class Par2Acceptance : public ::testing::TestWithParam<SubspaceWeighting> {};

TEST_P(Par2Acceptance, Order10RecoversInBandModesAndFit) {
  const Reference& ref = reference();
  N4sidOptions opt;
  opt.weighting = GetParam();
  opt.order = 10;
  const N4sidResult r = n4sid(ref.estimation, opt);
  const auto true_modes = modal_table(ref.truth), modes = modal_table(r.model);
  int checked = 0;
  for (const Mode& t : true_modes) {
    if (t.freq_hz > 100.0) continue;  // only modes inside the excited band are determined by the data
    const Mode* best = nullptr;
    for (const Mode& m : modes)
      if (!best || std::abs(m.freq_hz - t.freq_hz) < std::abs(best->freq_hz - t.freq_hz)) best = &m;
    ASSERT_NE(best, nullptr);
    EXPECT_LT(std::abs(best->freq_hz - t.freq_hz) / t.freq_hz, 0.005) << "mode at " << t.freq_hz << " Hz found at " << best->freq_hz;
    EXPECT_LT(std::abs(best->damping - t.damping) / t.damping, 0.10)
        << "mode at " << t.freq_hz << " Hz: damping " << best->damping << " vs " << t.damping;
    ++checked;
  }
  EXPECT_GE(checked, 3);
  const double fit = in_band_fit(r.model, r.input_offset, r.output_offset, ref.validation);
  EXPECT_GT(fit, ref.true_fit - 1.0) << "identified " << fit << " vs true " << ref.true_fit;
  std::cout << to_string(GetParam()) << ": in-band validation fit " << fit << " (true model " << ref.true_fit << ")\n";
}

TEST_P(Par2Acceptance, AutomaticOrderIsTen) {
  N4sidOptions opt;
  opt.weighting = GetParam();
  const N4sidResult r = n4sid(reference().estimation, opt);
  EXPECT_EQ(r.order, 10) << r.order_rule;
}

// The N4SID weighting (W1 = W2 = I) uses the oblique projection itself; on this
// 0-100 Hz chirp it needs the principal-angle guard of detail::oblique_projection
// (before it: in-band fit 88.4 against the true model's 99.7).
INSTANTIATE_TEST_SUITE_P(Weightings, Par2Acceptance,
                         ::testing::Values(SubspaceWeighting::n4sid, SubspaceWeighting::moesp, SubspaceWeighting::cva),
                         [](const auto& param_info) { return std::string(to_string(param_info.param)); });
