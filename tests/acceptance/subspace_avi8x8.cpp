// Acceptance of the foundation issue on the 8x8 isolator-like log
// (data/generate_examples.cpp): the identified frequency response matches the
// true one within 5 % over the excited band, every output's validation fit is
// within 2 points of the true model's, and the automatic order is the true 16.
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/subspace/n4sid.hpp>
#include <sysid/validate/fit.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace test_acceptance_subspace_avi8x8 {

using namespace sysid;

namespace {

const std::string kData = SYSID_TEST_DATA_DIR;

IoData load(const std::string& name) {
  LogOptions o;
  for (int k = 1; k <= 8; ++k) {
    o.inputs.push_back("u" + std::to_string(k));
    o.outputs.push_back("y" + std::to_string(k));
  }
  return read_log(kData + "/" + name, o);
}

Eigen::VectorXd validation_fit(const StateSpace& g, const Eigen::VectorXd& u_offset, const Eigen::VectorXd& y_offset, const IoData& val) {
  const Experiment& e = val.experiments.front();
  const Eigen::MatrixXd y_hat = simulate(g, e.u.rowwise() - u_offset.transpose()).rowwise() + y_offset.transpose();
  // Both records start from rest, so x0 = 0 is exact for the truth and right for the model.
  return fit_percent(e.y, y_hat);
}

}  // namespace

TEST(Avi8x8Acceptance, FrequencyResponseAndValidationFit) {
  const StateSpace truth = read_model_json(kData + "/avi8x8_true.json").model;
  const IoData est = load("avi8x8.csv"), val = load("avi8x8_val.csv");
  N4sidOptions opt;
  opt.order = 16;
  const N4sidResult r = n4sid(est, opt);
  // Relative error of the 8x8 response matrix (spectral norm) at each frequency of the excited band, 2..450 Hz.
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(2000, 2.0, 450.0);
  const auto g0 = frequency_response(truth, f), g1 = frequency_response(r.model, f);
  double worst = 0, worst_f = 0;
  for (std::size_t k = 0; k < g0.size(); ++k) {
    const double rel = Eigen::JacobiSVD<Eigen::MatrixXcd>(g1[k] - g0[k]).singularValues()(0) /
                       Eigen::JacobiSVD<Eigen::MatrixXcd>(g0[k]).singularValues()(0);
    if (rel > worst) {
      worst = rel;
      worst_f = f(static_cast<Eigen::Index>(k));
    }
  }
  EXPECT_LT(worst, 0.05) << "worst relative FRF error " << worst << " at " << worst_f << " Hz";
  const Eigen::VectorXd fit = validation_fit(r.model, r.input_offset, r.output_offset, val);
  const Eigen::VectorXd true_fit = validation_fit(truth, Eigen::VectorXd::Zero(8), Eigen::VectorXd::Zero(8), val);
  for (Eigen::Index c = 0; c < 8; ++c) EXPECT_GT(fit(c), true_fit(c) - 2.0) << "output " << c + 1;
  std::cout << "worst FRF error " << worst << " at " << worst_f << " Hz; validation fit " << fit.transpose() << " (true "
            << true_fit.transpose() << ")\n";
}

TEST(Avi8x8Acceptance, AutomaticOrderIsSixteen) {
  const N4sidResult r = n4sid(load("avi8x8.csv"), {});
  EXPECT_EQ(r.order, 16) << r.order_rule;
}

TEST(Avi8x8Acceptance, StabilizationDiagramCountsNoNoiseColumn) {
  // Orders 2..40 at the automatic horizon: the eight modes stand at 130-1 600 x
  // the wandering poles' level; a column at 444 Hz persists from order 27 at
  // ~2 x (noise that the high orders fit; with eight outputs the shape test
  // cannot tell it) and is named, not counted: the order stays the true 16.
  const StateSpace truth = read_model_json(kData + "/avi8x8_true.json").model;
  N4sidOptions o;
  o.order_rule = OrderRule::stabilization;
  o.stabilization_order_lo = 2;
  o.stabilization_order_hi = 40;
  const N4sidResult r = n4sid(load("avi8x8.csv"), o);
  const StabilizationDiagram& d = r.stabilization;
  std::cout << d.rule << "\n" << d.modes_table() << d.noise_columns_table();
  EXPECT_EQ(r.order, 16) << d.rule;
  std::vector<double> true_hz;  // modal_table sorts by frequency
  for (const Mode& m : modal_table(truth))
    if (m.complex_pair) true_hz.push_back(m.freq_hz);
  ASSERT_EQ(d.modes.size(), true_hz.size()) << d.modes_table() << d.noise_columns_table();
  for (std::size_t k = 0; k < true_hz.size(); ++k)
    EXPECT_NEAR(d.modes[k].freq_hz, true_hz[k], 0.005 * true_hz[k]) << "mode " << k + 1;
  for (const PhysicalMode& noise : d.noise_columns)
    for (const double f : true_hz) EXPECT_GT(std::abs(noise.freq_hz - f), 0.005 * f) << "a true mode refused at " << f << " Hz";
}

}  // namespace test_acceptance_subspace_avi8x8
