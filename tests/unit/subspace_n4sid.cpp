#include <sysid/core/discrete_riccati.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/excitation.hpp>
#include <sysid/signal/sos_filter.hpp>
#include <sysid/subspace/n4sid.hpp>
#include <sysid/validate/compare.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"

namespace test_unit_subspace_n4sid {

using namespace sysid;

namespace {

/// Worst relative frequency-response error over a grid spanning 0..0.45 fs
/// (the white-noise inputs excite the whole band), relative to the peak gain.
double relative_frf_error(const StateSpace& truth, const StateSpace& model) {
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(400, 0.001, 0.45);
  const auto g0 = frequency_response(truth, f), g1 = frequency_response(model, f);
  double peak = 0, worst = 0;
  for (std::size_t k = 0; k < g0.size(); ++k) {
    peak = std::max(peak, g0[k].cwiseAbs().maxCoeff());
    worst = std::max(worst, (g0[k] - g1[k]).cwiseAbs().maxCoeff());
  }
  return worst / peak;
}

IoData simulate_noisy(const StateSpace& sys, Eigen::Index n, std::uint64_t seed, double noise_to_signal) {
  const Eigen::MatrixXd u = test::white_noise(n, sys.inputs(), seed);
  Eigen::MatrixXd y = simulate(sys, u);
  for (Eigen::Index c = 0; c < y.cols(); ++c) {
    const double rms = std::sqrt(y.col(c).squaredNorm() / static_cast<double>(n));
    y.col(c) += test::white_noise(n, 1, seed + 100 + static_cast<std::uint64_t>(c), noise_to_signal * rms);
  }
  // Offsets that the identification must remove and report.
  Eigen::MatrixXd u_off = u.array() + 3.0;
  y.array() -= 1.5;
  return IoData(u_off, y, sys.Ts);
}

}  // namespace

class N4sidWeightings : public ::testing::TestWithParam<SubspaceWeighting> {};

TEST_P(N4sidWeightings, RecoversRandomMimoSystemsFromNoisyData) {
  // Seeded sweep over sizes, MIMO included; 1 % output noise, 6000 samples.
  int case_no = 0;
  for (auto [modes, m, l] : {std::tuple{1, 1, 1}, std::tuple{2, 1, 2}, std::tuple{3, 2, 2}, std::tuple{2, 3, 1}, std::tuple{4, 2, 3}}) {
    const StateSpace truth = test::random_modal_system(modes, m, l, 40 + static_cast<std::uint64_t>(case_no));
    const IoData data = simulate_noisy(truth, 6000, 7 + static_cast<std::uint64_t>(case_no), 0.01);
    N4sidOptions opt;
    opt.weighting = GetParam();
    opt.order = 2 * modes;
    const N4sidResult r = n4sid(data, opt);
    EXPECT_EQ(r.order, 2 * modes);
    EXPECT_LT(relative_frf_error(truth, r.model), 0.02) << "case " << case_no << " " << to_string(GetParam());
    EXPECT_NEAR(r.input_offset(0), 3.0, 0.05);
    for (Eigen::Index c = 0; c < l; ++c) EXPECT_GT(r.fit_percent(c), 95.0);
    ++case_no;
  }
}

TEST_P(N4sidWeightings, AutomaticOrderFindsTheTrueOrder) {
  for (int modes : {1, 2, 3}) {
    const StateSpace truth = test::random_modal_system(modes, 1, 2, 90 + static_cast<std::uint64_t>(modes));
    const IoData data = simulate_noisy(truth, 8000, 3, 0.01);
    N4sidOptions opt;
    opt.weighting = GetParam();
    opt.max_order = 12;
    const N4sidResult r = n4sid(data, opt);
    EXPECT_EQ(r.order, 2 * modes) << r.order_rule;
    EXPECT_NE(r.order_rule.find("SVC"), std::string::npos);
  }
}

TEST(N4sid, AutomaticOrderWhenSvcPenaltyExceedsEveryDrop) {
  // Six outputs, three inputs, 400 samples: SVC's penalty is log(N)/N * 15 =
  // 0.2 per order, so any order beyond 4 costs more than sigma_1^2 <= 1 and the
  // rule returns 0 for a 6th-order plant (the DaISy glass furnace's situation).
  // The canonical-correlation test finds the six modes and chooses, saying so.
  // The data are zero-mean and taken as they are: with the default mean removal a
  // 400-sample record at 1 % noise keeps a constant of order 1/sqrt(N) in the
  // outputs that no input explains (the inputs' sample mean is not exactly the
  // plant's), a 7th past-future correlation (r_7 = 0.87) the test rightly counts:
  // 7 is the innovation model's order for those data.
  const StateSpace truth = test::random_modal_system(3, 3, 6, 77);
  IoData data = simulate_noisy(truth, 400, 5, 0.01);
  data.experiments.front().u.array() -= 3.0;  // simulate_noisy's offsets
  data.experiments.front().y.array() += 1.5;
  N4sidOptions opt;
  opt.max_order = 12;
  opt.remove_means = false;
  const N4sidResult r = n4sid(data, opt);
  EXPECT_EQ(r.order, 6) << r.order_rule;
  EXPECT_NE(r.order_rule.find("canonical-correlation test"), std::string::npos) << r.order_rule;
  EXPECT_NE(r.order_rule.find("SVC (n = 0) is swamped"), std::string::npos) << r.order_rule;

  // At the fewest samples the block-Hankel step accepts (159 at horizon 8: 144
  // columns, 120 after the future inputs are projected out, against 48 + 72
  // dimensions) the test has no samples left for its noise level: the largest
  // singular-value gap chooses, with a warning.
  N4sidOptions short_record = opt;
  short_record.horizon = 8;
  IoData head = data;
  head.experiments.front().u.conservativeResize(159, Eigen::NoChange);
  head.experiments.front().y.conservativeResize(159, Eigen::NoChange);
  const N4sidResult g = n4sid(head, short_record);
  EXPECT_NE(g.order_rule.find("singular-value gap"), std::string::npos) << g.order_rule;
  bool warned = false;
  for (const auto& w : g.warnings) warned = warned || w.find("Bauer's SVC chose order 0") != std::string::npos;
  EXPECT_TRUE(warned);
}

TEST(N4sid, AutomaticOrderOnOutputsIndependentOfEverythingIsAnError) {
  // White outputs unrelated to the white inputs: no canonical correlation is
  // significant, so there are no dynamics to identify (NumericalError), rather
  // than a model of noise from the gap rule.
  const Eigen::MatrixXd u = test::white_noise(400, 3, 21), y = test::white_noise(400, 6, 22);
  N4sidOptions opt;
  opt.max_order = 12;
  try {
    (void)n4sid(IoData(u, y, 1.0), opt);
    FAIL() << "expected NumericalError";
  } catch (const NumericalError& e) {
    EXPECT_NE(std::string(e.what()).find("no dynamics to identify"), std::string::npos) << e.what();
  }
}

TEST_P(N4sidWeightings, InputThatLeavesPartOfTheBandEmpty) {
  // A multisine up to 0.3 fs leaves 0.3..0.5 fs empty: past and future inputs
  // are then nearly collinear (too wide a band for the decimated grid). The
  // N4SID weighting once fitted 28 % here against 91 % for the true model (the
  // oblique projection amplified noise along those directions); every
  // weighting must now come within 1 point of the true model on validation data.
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(4, 4);
  const double modes[2][2] = {{0.05, 0.02}, {0.12, 0.05}};  // (frequency / fs, damping ratio)
  for (int k = 0; k < 2; ++k) {
    const double w = 2 * std::numbers::pi * modes[k][0], zeta = modes[k][1];
    const double r = std::exp(-zeta * w), wd = w * std::sqrt(1 - zeta * zeta);
    a.block(2 * k, 2 * k, 2, 2) << r * std::cos(wd), r * std::sin(wd), -r * std::sin(wd), r * std::cos(wd);
  }
  const StateSpace truth(a, Eigen::Vector4d(0.0, 0.3, 0.0, 0.9), Eigen::RowVector4d(1.0, 0.0, 1.0, 0.0), Eigen::MatrixXd::Zero(1, 1), 1.0);
  MultisineOptions mo;
  mo.fs_hz = 1.0;
  mo.f_min_hz = 0.001;
  mo.f_max_hz = 0.3;
  mo.samples = 20000;
  mo.period = 4000;
  const Eigen::MatrixXd u = multisine(mo);
  Eigen::MatrixXd y = simulate(truth, u);
  y += test::white_noise(y.rows(), 1, 7, 0.02 * std::sqrt(y.squaredNorm() / static_cast<double>(y.rows())));
  const IoData est(u.topRows(14000), y.topRows(14000), 1.0);
  const Experiment val{u.bottomRows(6000), y.bottomRows(6000), ""};
  N4sidOptions opt;
  opt.weighting = GetParam();
  opt.order = 4;
  const N4sidResult r = n4sid(est, opt);
  EXPECT_EQ(r.decimation, 1);
  EXPECT_LT(r.past_future_min_sine, 0.1);  // the ill-conditioning is there and reported
  CompareOptions with_offsets;
  with_offsets.input_offset = r.input_offset;
  with_offsets.output_offset = r.output_offset;
  const double fit = compare(r.model, {}, val, with_offsets).fit_percent(0);
  const double true_fit = compare(truth, {}, val).fit_percent(0);
  EXPECT_GT(fit, true_fit - 1.0) << "identified " << fit << " vs true model " << true_fit;
}

INSTANTIATE_TEST_SUITE_P(AllWeightings, N4sidWeightings,
                         ::testing::Values(SubspaceWeighting::n4sid, SubspaceWeighting::moesp, SubspaceWeighting::cva),
                         [](const auto& param_info) { return std::string(to_string(param_info.param)); });

TEST(N4sid, KalmanGainOfAKnownInnovationModel) {
  // y = G u + H e with an innovation model whose predictor is stable (K is the
  // steady-state Kalman gain of the system for some noise, so A - K C is stable):
  // the identified one-step predictor must reach the innovation variance.
  StateSpace sys = test::random_modal_system(2, 1, 1, 5, 0.1);
  const KalmanFilterResult truth = steady_state_kalman_filter(sys.A, sys.C, 0.05 * Eigen::MatrixXd::Identity(4, 4),
                                                              Eigen::MatrixXd::Constant(1, 1, 0.09), Eigen::MatrixXd::Zero(4, 1));
  ASSERT_EQ(truth.status, KalmanFilterResult::Status::converged);
  const Eigen::Index n = 20000;
  const Eigen::MatrixXd u = test::white_noise(n, 1, 1), e = test::white_noise(n, 1, 2, 0.3);
  StateSpace aug(sys.A, Eigen::MatrixXd(4, 2), sys.C, Eigen::MatrixXd(1, 2), 1.0);
  aug.B << sys.B, truth.K;
  aug.D << sys.D, Eigen::MatrixXd::Ones(1, 1);
  Eigen::MatrixXd ue(n, 2);
  ue << u, e;
  const Eigen::MatrixXd y = simulate(aug, ue);
  N4sidOptions opt;
  opt.order = 4;
  opt.horizon = 20;
  const N4sidResult r = n4sid(IoData(u, y, 1.0), opt);
  ASSERT_EQ(r.K.rows(), 4);
  EXPECT_NEAR(r.noise_covariance(0, 0), 0.09, 0.09 * 0.05);
  // One-step prediction error of the identified predictor ~ innovation variance.
  StateSpace predictor(r.model.A - r.K * r.model.C, Eigen::MatrixXd(4, 2), r.model.C, Eigen::MatrixXd(1, 2), 1.0);
  predictor.B << r.model.B - r.K * r.model.D, r.K;
  predictor.D << r.model.D, Eigen::MatrixXd::Zero(1, 1);
  Eigen::MatrixXd uy(n, 2);
  uy << u.array() - r.input_offset(0), y.array() - r.output_offset(0);
  const Eigen::MatrixXd yhat = simulate(predictor, uy);
  const double mse = (y.array() - r.output_offset(0) - yhat.array()).matrix().bottomRows(n - 200).squaredNorm() / (n - 200);
  EXPECT_NEAR(mse, 0.09, 0.09 * 0.05);
}

TEST(N4sid, ExperimentsAreCombined) {
  const StateSpace truth = test::random_modal_system(2, 1, 1, 77);
  IoData a = simulate_noisy(truth, 1500, 1, 0.01);
  const IoData b = simulate_noisy(truth, 1500, 2, 0.01);
  a.add_experiment(b.experiments[0]);
  const N4sidResult r = n4sid(a, {.order = 4});
  EXPECT_LT(relative_frf_error(truth, r.model), 0.03);
}

TEST(N4sid, InitialStateIsEstimatedWhenItsResponseDecaysWithinTheRecord) {
  // Each record starts with a free decay from a large initial state (input
  // zero) and is forced by white noise only after that response has died out.
  // B/D/x0 take the samples where C A^t is below 1e-17 of its peak without the
  // x0 columns, in a narrower QR merged at the end: B and D come from those rows
  // alone, x0 from the others, so both halves of the merge are checked.
  const StateSpace truth = test::random_modal_system(2, 1, 1, 31, 0.05);
  const Eigen::Index samples = 6000, quiet = 3000;
  std::vector<Experiment> records;
  for (std::uint64_t e = 0; e < 2; ++e) {
    Eigen::MatrixXd u = test::white_noise(samples, 1, 50 + e);
    u.topRows(quiet).setZero();
    const double forced_rms = std::sqrt(simulate(truth, u).squaredNorm() / static_cast<double>(samples - quiet));
    Eigen::VectorXd x0 = test::white_noise(truth.order(), 1, 60 + e).col(0);
    const Eigen::MatrixXd free = simulate(truth, Eigen::MatrixXd::Zero(20, 1), x0);
    x0 *= 20.0 * forced_rms / free.cwiseAbs().maxCoeff();  // the transient starts at 20 x the forced RMS
    Eigen::MatrixXd y = simulate(truth, u, x0);
    y += test::white_noise(samples, 1, 70 + e, 1e-4 * forced_rms);
    records.push_back(Experiment{u, y, ""});
  }
  IoData data(records[0].u, records[0].y, truth.Ts);
  data.add_experiment(records[1]);
  const N4sidResult r = n4sid(data, {.order = 4});
  // Every forced sample lies in the reduced rows (the case exercises them).
  EXPECT_GE(r.bdx_samples_without_initial_response, 2 * (samples - quiet));
  EXPECT_LT(r.bdx_samples_without_initial_response, r.bdx_samples_used);
  EXPECT_LT(relative_frf_error(truth, r.model), 1e-3);
  // The first experiment's transient (from x0) and forced part (from B, D).
  const Experiment& first = data.experiments[0];
  const Eigen::MatrixXd u0 = first.u.rowwise() - r.input_offset.transpose();
  const Eigen::MatrixXd y_model = simulate(r.model, u0, r.x0).rowwise() + r.output_offset.transpose();
  auto relative_error = [&](Eigen::Index start, Eigen::Index count) {
    return (y_model.middleRows(start, count) - first.y.middleRows(start, count)).norm() /
           first.y.middleRows(start, count).norm();
  };
  // Measured 2026-11-24: about 1e-3 for each (the noise and the identified A, C);
  // with the merge left out (a mutation check) the forced error was 572 and the
  // FRF error 592.
  EXPECT_LT(relative_error(0, 200), 1e-2) << "transient";
  EXPECT_LT(relative_error(quiet, samples - quiet), 1e-2) << "forced response";
}

TEST(N4sid, EnforcedStabilityGivesAStableModel) {
  const StateSpace truth = test::random_modal_system(3, 1, 1, 8, 0.002);  // poles very near the unit circle
  const IoData data = simulate_noisy(truth, 3000, 4, 0.2);
  N4sidOptions opt;
  opt.order = 6;
  opt.enforce_stability = true;
  const N4sidResult r = n4sid(data, opt);
  EXPECT_LT(r.model.A.eigenvalues().cwiseAbs().maxCoeff(), 1.0);
}

TEST(N4sid, InputAndOutputScalesOfNineDecadesGiveTheSameModel) {
  // Hardening (issue 8): inputs scaled by 1e-9 and 1e9, outputs by the inverse or
  // the same factor, must give the same model up to that scale — the algorithm
  // scales its data, it must not lose digits or change the chosen order.
  const StateSpace truth = test::random_modal_system(2, 2, 2, 77);
  const IoData base = simulate_noisy(truth, 4000, 78, 0.01);
  N4sidOptions opt;
  opt.order = 0;  // automatic: the chosen order must not depend on the units
  const N4sidResult reference = n4sid(base, opt);
  for (double su : {1e-9, 1e9})
    for (double sy : {1e-9, 1e9}) {
      IoData scaled = base;
      scaled.experiments.front().u *= su;
      scaled.experiments.front().y *= sy;
      const N4sidResult r = n4sid(scaled, opt);
      EXPECT_EQ(r.order, reference.order) << "u x " << su << ", y x " << sy;
      // G_scaled = (sy / su) G: compare the rescaled response.
      StateSpace back = r.model;
      back.B *= su;
      back.D *= su;
      back.C /= sy;
      back.D /= sy;
      EXPECT_LT(relative_frf_error(reference.model, back), 1e-6) << "u x " << su << ", y x " << sy;
    }
}

TEST(N4sid, ConstantInputIsRejected) {
  const Eigen::MatrixXd u = Eigen::MatrixXd::Constant(500, 1, 2.0);
  const IoData data(u, test::white_noise(500, 1, 1), 1.0);
  try {
    n4sid(data, {.order = 2});
    FAIL();
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("constant"), std::string::npos);
  }
}

TEST(N4sid, OrderAboveHorizonIsAPreconditionError) {
  const IoData data(test::white_noise(500, 1, 1), test::white_noise(500, 1, 2), 1.0);
  N4sidOptions opt;
  opt.order = 8;
  opt.horizon = 5;
  EXPECT_THROW(n4sid(data, opt), std::invalid_argument);
}

TEST(N4sid, OversampledDataAreIdentifiedOnADecimatedGrid) {
  // Modes at 0.01 and 0.03 of fs, input band-limited to 0.05 fs: the subspace
  // step runs on a grid decimated by an odd factor and A is mapped back; the
  // frequency response in the excited band must still be right.
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(4, 4);
  for (int k = 0; k < 2; ++k) {
    const double w = 2 * std::numbers::pi * (k == 0 ? 0.01 : 0.03), r = std::exp(-0.03 * w);
    a.block(2 * k, 2 * k, 2, 2) << r * std::cos(w), r * std::sin(w), -r * std::sin(w), r * std::cos(w);
  }
  const StateSpace truth(a, Eigen::MatrixXd::Ones(4, 1), Eigen::RowVector4d(1.0, 0.5, -0.7, 0.2), Eigen::MatrixXd::Zero(1, 1), 1.0);
  const SecondOrderSections lp = butterworth(8, BandType::lowpass, 0.05, 0.0, 1.0);
  const Eigen::MatrixXd u = sos_filter(lp, test::white_noise(30000, 1, 5));
  Eigen::MatrixXd y = simulate(truth, u);
  y += test::white_noise(30000, 1, 6, 0.001 * std::sqrt(y.squaredNorm() / 30000.0));
  const N4sidResult r = n4sid(IoData(u, y, 1.0), {.weighting = SubspaceWeighting::moesp, .order = 4});
  EXPECT_GE(r.decimation, 3);
  EXPECT_EQ(r.decimation % 2, 1);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(100, 0.002, 0.045);
  const auto g0 = frequency_response(truth, f), g1 = frequency_response(r.model, f);
  double worst = 0, peak = 0;
  for (std::size_t k = 0; k < g0.size(); ++k) {
    worst = std::max(worst, std::abs(g0[k](0, 0) - g1[k](0, 0)));
    peak = std::max(peak, std::abs(g0[k](0, 0)));
  }
  EXPECT_LT(worst / peak, 0.02);
}

TEST(N4sid, DecimatedGridStillGivesAKalmanGain) {
  // The same oversampled plant with innovation noise (y = G u + H e, H sharing
  // the plant's poles): on the decimated grid K comes from the residuals at the
  // original rate, and the one-step predictor must reach the innovation variance.
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(4, 4);
  for (int k = 0; k < 2; ++k) {
    const double w = 2 * std::numbers::pi * (k == 0 ? 0.01 : 0.03), r = std::exp(-0.03 * w);
    a.block(2 * k, 2 * k, 2, 2) << r * std::cos(w), r * std::sin(w), -r * std::sin(w), r * std::cos(w);
  }
  const StateSpace sys(a, Eigen::MatrixXd::Ones(4, 1), Eigen::RowVector4d(1.0, 0.5, -0.7, 0.2), Eigen::MatrixXd::Zero(1, 1), 1.0);
  const double innovation_variance = 1e-4;
  const KalmanFilterResult truth = steady_state_kalman_filter(sys.A, sys.C, 1e-5 * Eigen::MatrixXd::Identity(4, 4),
                                                              Eigen::MatrixXd::Constant(1, 1, 1e-5), Eigen::MatrixXd::Zero(4, 1));
  ASSERT_EQ(truth.status, KalmanFilterResult::Status::converged);
  const Eigen::Index n = 30000;
  const Eigen::MatrixXd u = sos_filter(butterworth(8, BandType::lowpass, 0.05, 0.0, 1.0), test::white_noise(n, 1, 5));
  const Eigen::MatrixXd e = test::white_noise(n, 1, 9, std::sqrt(innovation_variance));
  StateSpace aug(sys.A, Eigen::MatrixXd(4, 2), sys.C, Eigen::MatrixXd(1, 2), 1.0);
  aug.B << sys.B, truth.K;
  aug.D << sys.D, Eigen::MatrixXd::Ones(1, 1);
  Eigen::MatrixXd ue(n, 2);
  ue << u, e;
  const Eigen::MatrixXd y = simulate(aug, ue);
  const N4sidResult r = n4sid(IoData(u, y, 1.0), {.weighting = SubspaceWeighting::moesp, .order = 4});
  ASSERT_GE(r.decimation, 3);
  ASSERT_EQ(r.K.rows(), 4) << (r.warnings.empty() ? "" : r.warnings.back());
  const Experiment data{u, y, ""};
  CompareOptions simulation;
  simulation.input_offset = r.input_offset;
  simulation.output_offset = r.output_offset;
  CompareOptions one_step = simulation;
  one_step.predict_steps = 1;
  const Eigen::MatrixXd residual = y - compare(r.model, r.K, data, one_step).y_hat;
  const double mse = residual.bottomRows(n - 500).squaredNorm() / static_cast<double>(n - 500);
  EXPECT_NEAR(mse, innovation_variance, 0.1 * innovation_variance);
  // Without K the same model predicts no better than it simulates: far worse.
  const double simulation_mse =
      (y - compare(r.model, {}, data, simulation).y_hat)
          .bottomRows(n - 500)
          .squaredNorm() /
      static_cast<double>(n - 500);
  EXPECT_GT(simulation_mse, 3 * innovation_variance);
}

TEST(N4sid, BandLimitedModelFollowsTheFilterAboveTheBand) {
  const StateSpace truth = test::random_modal_system(2, 1, 1, 12);
  const IoData data = simulate_noisy(truth, 5000, 3, 0.01);
  N4sidOptions opt;
  opt.order = 4;
  opt.band_limit_hz = 0.2;
  opt.band_limit_order = 4;
  const N4sidResult r = n4sid(data, opt);
  ASSERT_TRUE(r.band_limited);
  EXPECT_EQ(r.model.order(), 4 + 4);
  const SecondOrderSections lp = butterworth(4, BandType::lowpass, 0.2, 0.0, 1.0);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(40, 0.01, 0.45);
  const auto g0 = frequency_response(truth, f), g1 = frequency_response(r.model, f);
  for (std::size_t k = 0; k < g0.size(); ++k) {
    const std::complex<double> expected = g0[k](0, 0) * sos_frequency_response(lp, f(static_cast<Eigen::Index>(k)));
    EXPECT_LT(std::abs(g1[k](0, 0) - expected), 0.03 * std::max(std::abs(g0[k](0, 0)), 0.1)) << "f = " << f(static_cast<Eigen::Index>(k));
  }
}

}  // namespace test_unit_subspace_n4sid
