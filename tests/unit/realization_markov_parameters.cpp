// Tests for include/sysid/realization/markov_parameters.hpp: Markov parameters
// from a state-space model and from FIR taps, and hammer-tap deconvolution.
#include <sysid/core/modal_table.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/realization/era.hpp>
#include <sysid/realization/markov_parameters.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <string>
#include <vector>
#include "checks.hpp"
#include "random_systems.hpp"

namespace test_unit_realization_markov_parameters {

namespace {

using Eigen::MatrixXd;

constexpr double kTs = 0.001;  // 1 kHz sampling

using sysid::test::has_warning;
using sysid::test::relative_error;
using sysid::test::rotated_modal_system;

/// One hammer-tap record for input `which` of m: `taps` impacts of random
/// amplitude at random times in the first half, each of the given sample shape,
/// the record starting at rest.
MatrixXd hammer_record(Eigen::Index N, int m, int which, int taps, const std::vector<double>& shape, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> amp(0.5, 1.5);
  std::uniform_int_distribution<Eigen::Index> at(5, N / 2);
  MatrixXd u = MatrixXd::Zero(N, m);
  for (int t = 0; t < taps; ++t) {
    const Eigen::Index k0 = at(rng);
    const double a = amp(rng);
    for (std::size_t i = 0; i < shape.size(); ++i) u(k0 + static_cast<Eigen::Index>(i), which) += a * shape[i];
  }
  return u;
}

/// A hard-tip impact, two samples: |U| falls from 1.5 at DC to 0.5 at Nyquist,
/// so the whole band is excited (a soft tip, several samples long, would leave
/// the upper band to the regularisation).
const std::vector<double> kHardTip{1.0, 0.5};

TEST(RealizationMarkovParameters, FromStateSpaceEqualsSimulatedImpulseResponse) {
  // Column j of y for a unit impulse on input j is h[k](:, j): exact up to rounding.
  const sysid::StateSpace sys = rotated_modal_system({20.0, 70.0}, {0.02, 0.03}, 2, 3, 1, kTs);
  const sysid::MarkovParameters mp = sysid::markov_parameters(sys, 30);
  ASSERT_EQ(mp.count(), 31);
  EXPECT_EQ(mp.inputs(), 2);
  EXPECT_EQ(mp.outputs(), 3);
  EXPECT_EQ(mp.Ts, sys.Ts);
  for (int j = 0; j < 2; ++j) {
    MatrixXd u = MatrixXd::Zero(31, 2);
    u(0, j) = 1.0;
    const MatrixXd y = sysid::simulate(sys, u);
    for (int k = 0; k <= 30; ++k)
      EXPECT_LT((y.row(k).transpose() - mp.h[static_cast<std::size_t>(k)].col(j)).norm(), 1e-12) << "k=" << k;
  }
  EXPECT_THROW(sysid::markov_parameters(sys, -1), std::invalid_argument);
  sysid::StateSpace cont = sys;
  cont.Ts = 0.0;
  EXPECT_THROW(sysid::markov_parameters(cont, 5), std::invalid_argument);
}

TEST(RealizationMarkovParameters, FromFirCopiesAndValidates) {
  std::vector<MatrixXd> fir{MatrixXd::Constant(2, 1, 1.0), MatrixXd::Constant(2, 1, 0.5)};
  const sysid::MarkovParameters mp = sysid::markov_from_fir(fir, 0.01, {"act"}, {"a", "b"});
  EXPECT_EQ(mp.h[1], fir[1]);
  EXPECT_EQ(mp.input_name(0), "act");
  EXPECT_EQ(mp.output_name(1), "b");
  EXPECT_THROW(sysid::markov_from_fir({}, 0.01), std::invalid_argument);
  EXPECT_THROW(sysid::markov_from_fir(fir, 0.0), std::invalid_argument);
  fir[1] = MatrixXd::Zero(3, 1);
  EXPECT_THROW(sysid::markov_from_fir(fir, 0.01), std::invalid_argument);
  fir[1] = MatrixXd::Constant(2, 1, std::nan(""));
  EXPECT_THROW(sysid::markov_from_fir(fir, 0.01), std::invalid_argument);
}

TEST(RealizationMarkovParameters, HammerTapDeconvolutionRecoversImpulseResponse) {
  // One hammer position, 3 sensors, Ts = 1 ms, modes at 45, 120, 260 Hz with
  // zeta 8, 3, 2.5 %: the slowest decays as exp(-2 pi 45 0.08 t), to 1e-3 of its
  // start within the 300-sample window (truncation negligible). Four records
  // with 4 taps each, sensor noise 1 % of each record's peak response (23 dB
  // SNR over the records). Least squares with q = 300 unknowns from N = 4000
  // equations: relative error energy ~ (q / N) / SNR = 0.075 * 0.005, i.e.
  // ~2 % RMS for a white force; measured 3.4 % (sparse impacts make Phi^T Phi
  // less uniform than a white force's); asserted 6 %, and ERA frequencies within 1 %.
  const sysid::StateSpace sys = rotated_modal_system({45.0, 120.0, 260.0}, {0.08, 0.03, 0.025}, 1, 3, 3, kTs);
  std::mt19937_64 rng(4);
  std::normal_distribution<double> g(0.0, 1.0);
  sysid::IoData taps;
  taps.Ts = sys.Ts;
  const Eigen::Index N = 1000;
  for (int rec = 0; rec < 4; ++rec) {
    const MatrixXd u = hammer_record(N, 1, 0, 4, kHardTip, rng);
    MatrixXd y = sysid::simulate(sys, u);
    for (Eigen::Index c = 0; c < y.cols(); ++c) {
      const double sigma = 0.01 * y.col(c).cwiseAbs().maxCoeff();
      for (Eigen::Index k = 0; k < N; ++k) y(k, c) += sigma * g(rng);
    }
    taps.add_experiment({u, y, "tap" + std::to_string(rec)});
  }
  sysid::ImpulseDeconvolutionOptions o;
  o.length = 300;
  const sysid::ImpulseDeconvolutionResult r = sysid::impulse_response_from_taps(taps, o);
  ASSERT_EQ(r.markov.count(), 300);
  EXPECT_EQ(r.markov.inputs(), 1);
  EXPECT_EQ(r.markov.outputs(), 3);
  EXPECT_EQ(r.equations, 4 * N);
  const sysid::MarkovParameters truth = sysid::markov_parameters(sys, 299);
  EXPECT_LT(relative_error(r.markov.h, truth.h, 300), 0.06);
  EXPECT_FALSE(has_warning(r.warnings, "not decayed"));
  sysid::EraOptions eo;
  eo.order = 6;
  const sysid::EraResult era = sysid::era(r.markov, eo);
  const auto me = sysid::modal_table(era.model), mt = sysid::modal_table(sys);
  ASSERT_EQ(me.size(), mt.size());
  for (std::size_t i = 0; i < mt.size(); ++i) EXPECT_NEAR(me[i].freq_hz / mt[i].freq_hz, 1.0, 0.01) << "mode " << i;
}

TEST(RealizationMarkovParameters, RegularisationTamesASoftTip) {
  // A soft tip, [0.4 1 0.7 0.2]: |U| falls from 2.3 at DC to 0.1 at Nyquist, so
  // unregularised deconvolution amplifies the sensor noise up to 23x near
  // Nyquist. Tikhonov regularisation at 0.1 of the RMS column norm damps those
  // bands; the total error must drop (the bias it adds is in bands where the
  // true response is small: all modes lie below 0.3 of Nyquist).
  const sysid::StateSpace sys = rotated_modal_system({45.0, 120.0}, {0.08, 0.05}, 1, 2, 9, kTs);
  std::mt19937_64 rng(10);
  std::normal_distribution<double> g(0.0, 1.0);
  sysid::IoData taps;
  taps.Ts = sys.Ts;
  for (int rec = 0; rec < 4; ++rec) {
    const MatrixXd u = hammer_record(800, 1, 0, 3, {0.4, 1.0, 0.7, 0.2}, rng);
    MatrixXd y = sysid::simulate(sys, u);
    for (Eigen::Index c = 0; c < y.cols(); ++c) {
      const double sigma = 0.01 * y.col(c).cwiseAbs().maxCoeff();
      for (Eigen::Index k = 0; k < y.rows(); ++k) y(k, c) += sigma * g(rng);
    }
    taps.add_experiment({u, y, "soft"});
  }
  const sysid::MarkovParameters truth = sysid::markov_parameters(sys, 199);
  sysid::ImpulseDeconvolutionOptions o;
  o.length = 200;
  o.regularization = 0.0;
  const sysid::ImpulseDeconvolutionResult plain = sysid::impulse_response_from_taps(taps, o);
  o.regularization = 0.1;
  const sysid::ImpulseDeconvolutionResult tamed = sysid::impulse_response_from_taps(taps, o);
  const double e_plain = relative_error(plain.markov.h, truth.h, 200);
  const double e_tamed = relative_error(tamed.markov.h, truth.h, 200);
  EXPECT_LT(e_tamed, 0.7 * e_plain) << "plain " << e_plain << ", regularised " << e_tamed;
  EXPECT_GT(tamed.lambda, 0.0);
  EXPECT_GT(plain.condition, 20.0);  // the soft tip's spectral ratio shows in the conditioning
}

TEST(RealizationMarkovParameters, DeconvolutionIsExactWithoutNoiseAndRegularisation) {
  // Noise-free records, lambda = 0: Phi Theta = Y is consistent, and the QR
  // solution is exact up to rounding times cond(Phi).
  // Two inputs tapped in turn (MIMO regression), 2 outputs.
  const sysid::StateSpace sys = rotated_modal_system({60.0, 150.0}, {0.08, 0.05}, 2, 2, 5, kTs);
  std::mt19937_64 rng(6);
  sysid::IoData taps;
  taps.Ts = sys.Ts;
  for (int rec = 0; rec < 4; ++rec) {
    const MatrixXd u = hammer_record(500, 2, rec % 2, 3, kHardTip, rng);
    taps.add_experiment({u, sysid::simulate(sys, u), "t"});
  }
  sysid::ImpulseDeconvolutionOptions o;
  o.length = 200;
  o.regularization = 0.0;
  const sysid::ImpulseDeconvolutionResult r = sysid::impulse_response_from_taps(taps, o);
  // The truncated tail beyond 200 samples (exp(-2 pi 60 0.08 0.2) ~ 2e-3 of the
  // start) is the only model error; it leaks into the estimate at its own size.
  EXPECT_LT(relative_error(r.markov.h, sysid::markov_parameters(sys, 199).h, 200), 3e-3);
  EXPECT_EQ(r.lambda, 0.0);
  EXPECT_GT(r.condition, 1.0);
}

TEST(RealizationMarkovParameters, DeconvolutionWarnsAndThrows) {
  const sysid::StateSpace sys = rotated_modal_system({30.0}, {0.01}, 1, 1, 7, kTs);
  std::mt19937_64 rng(8);
  const MatrixXd u = hammer_record(500, 1, 0, 1, kHardTip, rng);
  const sysid::IoData taps(u, sysid::simulate(sys, u), sys.Ts);
  sysid::ImpulseDeconvolutionOptions o;
  o.length = 50;  // a 30 Hz mode with 1 % damping rings far longer than 50 ms
  EXPECT_TRUE(has_warning(sysid::impulse_response_from_taps(taps, o).warnings, "not decayed"));
  o.length = 0;
  EXPECT_THROW(sysid::impulse_response_from_taps(taps, o), std::invalid_argument);
  o.length = 501;
  EXPECT_THROW(sysid::impulse_response_from_taps(taps, o), std::invalid_argument);  // more unknowns than samples
  o.length = 50;
  o.regularization = -1.0;
  EXPECT_THROW(sysid::impulse_response_from_taps(taps, o), std::invalid_argument);
  o.regularization = 0.0;
  const sysid::IoData silent(MatrixXd::Zero(500, 1), MatrixXd::Zero(500, 1), sys.Ts);
  EXPECT_THROW(sysid::impulse_response_from_taps(silent, o), sysid::NumericalError);
}

}  // namespace

}  // namespace test_unit_realization_markov_parameters
