// Acceptance of the prediction-error issue on the Par2 disturbance log
// (GW of eq. 5 driven by white noise, 1 % output noise): ARMA(16,8) finds both
// resonances of eq. (5), and its innovation model reduced to order 4 by modal
// truncation of the 20-40 Hz band keeps each within 1 % in frequency; AR(16)
// does the same when estimated by the modified Yule-Walker method (least squares,
// Burg and Yule-Walker resolve only the 25.9 Hz mode on this log: the sensor
// noise makes it ARMA(4, 4), data/README.md). The spectra of ARMA(16,8) and of
// the least-squares AR(16) agree with the log's Welch estimate.
#include <sysid/core/modal_table.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/pem/arx.hpp>
#include <sysid/pem/polynomial_model.hpp>
#include <sysid/pem/prediction_error.hpp>
#include <sysid/reduce/modal_truncation.hpp>
#include <sysid/spectral/confidence.hpp>
#include <sysid/spectral/model_spectrum.hpp>
#include <sysid/spectral/welch.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <iostream>
#include <numbers>

namespace test_acceptance_pem_par2_gw {

using namespace sysid;

namespace {

/// Natural frequencies of the two quadratic factors of GW(z), eq. (5), at 2 kHz.
std::vector<double> true_frequencies_hz() {
  std::vector<double> f;
  for (const auto& [c1, c0] : {std::pair{-1.992, 0.9986}, std::pair{-1.963, 0.9729}}) {
    const std::complex<double> z = (-c1 + std::sqrt(std::complex<double>(c1 * c1 - 4.0 * c0))) / 2.0;
    f.push_back(std::abs(std::log(z)) * 2000.0 / (2.0 * std::numbers::pi));
  }
  return f;  // about 25.88 Hz and 31.90 Hz
}

/// The 20-40 Hz modes of a time-series model A(q) y = C(q) e, after modal
/// truncation of its innovation form to that band (keeping the DC gain), checked
/// against eq. (5) within 1 % in natural frequency.
void expect_both_resonances_within_one_percent(const PolynomialModel& model, const std::string& what) {
  const InnovationStateSpace ss = to_innovation_state_space(model);
  // The time series' innovation form: input = the innovation.
  const StateSpace noise_model(ss.model.A, ss.K, ss.model.C, Eigen::MatrixXd::Identity(1, 1), ss.model.Ts);
  ModalTruncationOptions mo;
  mo.f_lo_hz = 20.0;
  mo.f_hi_hz = 40.0;
  mo.keep_dc_gain = true;
  const ReductionResult reduced = modal_truncation(noise_model, mo);
  EXPECT_EQ(reduced.order, 4) << what;
  const auto modes = modal_table(reduced.model);
  ASSERT_EQ(modes.size(), 2u) << what;
  const std::vector<double> truth = true_frequencies_hz();
  for (std::size_t k = 0; k < 2; ++k) {
    std::cout << what << " mode " << k + 1 << ": " << modes[k].freq_hz << " Hz (eq. 5: " << truth[k] << " Hz), damping "
              << modes[k].damping << "\n";
    EXPECT_LT(std::abs(modes[k].freq_hz - truth[k]) / truth[k], 0.01) << what;
  }
}

IoData disturbance_log() {
  LogOptions lo;
  lo.outputs = {"y"};
  return read_log(std::string(SYSID_TEST_DATA_DIR) + "/par2_gw.csv", lo);
}

}  // namespace

TEST(Par2Disturbance, Ar16ByModifiedYuleWalkerReducedToOrder4KeepsBothResonancesWithinOnePercent) {
  const LinearPolynomialResult r = ar(disturbance_log(), {.na = 16, .method = ArMethod::modified_yule_walker});
  expect_both_resonances_within_one_percent(r.models.front(), "AR(16), modified Yule-Walker");
}

TEST(Par2Disturbance, Arma16ReducedToOrder4KeepsBothResonancesWithinOnePercent) {
  PemOptions o;
  o.na = 16;
  o.nc = 8;
  const PemResult r = pem(disturbance_log(), o);
  ASSERT_EQ(r.status, PemResult::Status::converged) << r.termination;
  expect_both_resonances_within_one_percent(r.model, "ARMA(16, 8)");
}

namespace {

/// The model's spectrum against the log's Welch estimate (nfft 4096, Hann, 50 %) in a band.
SpectrumAgreement spectrum_against_welch(const PolynomialModel& model, const IoData& log, double f_lo, double f_hi,
                                         const std::string& what) {
  WelchOptions o;
  o.nfft = 4096;
  const PowerSpectrum ps = welch_psd(log.experiments.front().y, 1.0 / log.Ts, o);
  const InnovationStateSpace ss = to_innovation_state_space(model);
  const ModelSpectrum s =
      model_output_spectrum(ss.model, ss.K, Eigen::MatrixXd::Constant(1, 1, model.noise_variance), ps.freq_hz);
  const auto [lo, hi] = psd_confidence_factors(ps.dof, 0.95);
  const SpectrumAgreement a = spectrum_agreement(ps.psd.col(0), s.output_psd.col(0), ps.freq_hz, f_lo, f_hi, lo, hi);
  std::cout << what << " spectrum, " << f_lo << "-" << f_hi << " Hz: level " << a.median_db << " dB, shape " << a.mean_abs_db
            << " dB, " << 100 * a.fraction_inside << " % of " << a.bins << " bins inside the 95 % band\n";
  return a;
}

}  // namespace

// "AR and ARMA spectra against the periodogram" (issue 4): ARMA(16,8) matches the
// Welch estimate in level and shape over the whole band and around the two
// resonances; the least-squares AR(16) over the whole band (around the resonances
// it is 2-3 dB low: it spends poles on the sensor-noise floor). The modified
// Yule-Walker AR(16), whose poles are right, is only printed: its spectrum
// sigma^2/|A|^2 has no numerator for the noise-shaped log and sits ~27 dB above the
// estimate at the resonances (data/README.md).
TEST(Par2Disturbance, ArmaAndArSpectraAgreeWithTheWelchEstimate) {
  const IoData log = disturbance_log();
  PemOptions o;
  o.na = 16;
  o.nc = 8;
  const PemResult arma = pem(log, o);
  ASSERT_EQ(arma.status, PemResult::Status::converged) << arma.termination;
  const SpectrumAgreement whole = spectrum_against_welch(arma.model, log, 1.0, 1000.0, "ARMA(16, 8)");
  EXPECT_LT(std::abs(whole.median_db), 0.5);
  EXPECT_LT(whole.mean_abs_db, 1.5);
  EXPECT_GT(whole.fraction_inside, 0.85);
  const SpectrumAgreement resonances = spectrum_against_welch(arma.model, log, 15.0, 45.0, "ARMA(16, 8)");
  EXPECT_LT(std::abs(resonances.median_db), 0.5);
  EXPECT_LT(resonances.mean_abs_db, 1.5);
  EXPECT_GT(resonances.fraction_inside, 0.8);

  const LinearPolynomialResult ls = ar(log, {.na = 16});
  const SpectrumAgreement ar_whole = spectrum_against_welch(ls.models.front(), log, 1.0, 1000.0, "AR(16), least squares");
  EXPECT_LT(std::abs(ar_whole.median_db), 0.5);
  EXPECT_LT(ar_whole.mean_abs_db, 2.0);
  spectrum_against_welch(ls.models.front(), log, 15.0, 45.0, "AR(16), least squares");
  const LinearPolynomialResult myw = ar(log, {.na = 16, .method = ArMethod::modified_yule_walker});
  spectrum_against_welch(myw.models.front(), log, 15.0, 45.0, "AR(16), modified Yule-Walker");
}

}  // namespace test_acceptance_pem_par2_gw
