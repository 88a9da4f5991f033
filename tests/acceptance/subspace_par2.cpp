// Acceptance of the foundation issue on the Par2 piezo log (data/generate_examples.cpp):
// N4SID, MOESP and CVA at order 10 recover every mode inside the excited band
// (natural frequency within 0.5 %, damping ratio within 10 %), and reach an
// in-band validation fit within 1 point of the true model's; --order auto picks 10.
#include <sysid/core/modal_table.hpp>
#include <sysid/subspace/n4sid.hpp>

#include <gtest/gtest.h>

#include <iostream>
#include <vector>

#include "par2_reference.hpp"
#include "sanitizers.hpp"

namespace test_acceptance_subspace_par2 {

using namespace sysid;
using test::par2_in_band_fit;
using test::par2_reference;

class Par2Acceptance : public ::testing::TestWithParam<SubspaceWeighting> {};

TEST_P(Par2Acceptance, Order10RecoversInBandModesAndFit) {
  const auto& ref = par2_reference();
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
  const double fit = par2_in_band_fit(r.model, r.input_offset, r.output_offset, ref.validation);
  EXPECT_GT(fit, ref.true_fit - 1.0) << "identified " << fit << " vs true " << ref.true_fit;
  std::cout << to_string(GetParam()) << ": in-band validation fit " << fit << " (true model " << ref.true_fit << ")\n";
}

TEST_P(Par2Acceptance, AutomaticOrderIsTen) {
  N4sidOptions opt;
  opt.weighting = GetParam();
  const N4sidResult r = n4sid(par2_reference().estimation, opt);
  EXPECT_EQ(r.order, 10) << r.order_rule;
}

// The chirp leaves 90 % of the Nyquist band empty: even on the grid decimated
// by 5 the block-Hankel matrix has cond ~5e11, the double Gram matrix is
// refused, and the automatic route forms it in double-double. Its model must
// be the QR route's (whose R is the less accurate of the two; see
// hankel/block_hankel.hpp).
TEST_P(Par2Acceptance, DoubleDoubleGramRouteGivesTheQrRouteModel) {
  const auto& ref = par2_reference();
  N4sidOptions opt;
  opt.weighting = GetParam();
  opt.order = 10;
  const N4sidResult automatic = n4sid(ref.estimation, opt);
  EXPECT_EQ(automatic.route_used, HankelRoute::cholesky_double_double);
  opt.route = HankelRoute::qr;
  const N4sidResult qr = n4sid(ref.estimation, opt);
  EXPECT_EQ(qr.route_used, HankelRoute::qr);
  const auto modes_dd = modal_table(automatic.model), modes_qr = modal_table(qr.model);
  ASSERT_EQ(modes_dd.size(), modes_qr.size());
  for (std::size_t k = 0; k < modes_dd.size(); ++k) {
    if (modes_qr[k].freq_hz > 100.0) continue;  // outside the excited band the data determine nothing
    EXPECT_NEAR(modes_dd[k].freq_hz / modes_qr[k].freq_hz, 1.0, 1e-4) << "mode " << k;
    EXPECT_NEAR(modes_dd[k].damping / modes_qr[k].damping, 1.0, 1e-2) << "mode " << k;
  }
  const double fit_dd = par2_in_band_fit(automatic.model, automatic.input_offset, automatic.output_offset, ref.validation);
  const double fit_qr = par2_in_band_fit(qr.model, qr.input_offset, qr.output_offset, ref.validation);
  EXPECT_NEAR(fit_dd, fit_qr, 0.05);
}

// Issue 34 item 3: at every horizon from 15 to 60 every weighting writes a stable
// model within 2 points of the true model's in-band validation fit (99.7). The
// subspace poles alone ranged 81.0-99.0 over these horizons (a heavily damped
// mode at the band's edge left near the projection's noise floor at long
// horizons); a given horizon other than the automatic one (20 here) has its poles
// refined on the simulation error from two raced starts (n4sid.hpp,
// refine_poles), which reaches the true model's poles. Under the sanitizers:
// horizon 60 with MOESP only (the refinement's path; each call costs ~30 s there).
TEST_P(Par2Acceptance, EveryHorizonFromFifteenToSixtyGivesAStableModelWithinTwoPointsOfTheTrueFit) {
  const auto& ref = par2_reference();
  const std::vector<int> horizons = !test::kSanitized                           ? std::vector<int>{15, 20, 25, 30, 40, 50, 60}
                                    : GetParam() == SubspaceWeighting::moesp ? std::vector<int>{60}
                                                                              : std::vector<int>{};
  for (const int horizon : horizons) {
    N4sidOptions opt;
    opt.weighting = GetParam();
    opt.order = 10;
    opt.horizon = horizon;
    const N4sidResult r = n4sid(ref.estimation, opt);
    const double radius = r.model.A.eigenvalues().cwiseAbs().maxCoeff();
    const double fit = par2_in_band_fit(r.model, r.input_offset, r.output_offset, ref.validation);
    std::cout << to_string(GetParam()) << " horizon " << horizon << ": spectral radius " << radius << ", in-band validation fit "
              << fit << " (true model " << ref.true_fit << "); " << (r.refinement.empty() ? "not refined" : r.refinement) << "\n";
    EXPECT_LT(radius, 1.0) << "horizon " << horizon;
    EXPECT_GT(fit, ref.true_fit - 2.0) << "horizon " << horizon;
    EXPECT_EQ(r.horizon, horizon);
    EXPECT_EQ(r.horizon_rule, "given by the user");
    // The automatic horizon for order 10 (20) keeps the subspace poles; every other is refined.
    EXPECT_EQ(r.poles_refined, horizon != 20) << "horizon " << horizon << ": " << r.refinement;
  }
  // refine_poles = never: the subspace poles as they are (the peers' comparison in bench/).
  N4sidOptions never;
  never.weighting = GetParam();
  never.order = 10;
  never.horizon = 60;
  never.refine_poles = PoleRefinementMode::never;
  const N4sidResult plain = n4sid(ref.estimation, never);
  EXPECT_FALSE(plain.poles_refined);
  EXPECT_TRUE(plain.refinement.empty());
}

// The N4SID weighting (W1 = W2 = I) uses the oblique projection itself; on this
// 0-100 Hz chirp it needs the principal-angle guard of detail::oblique_projection
// (before it: in-band fit 88.4 against the true model's 99.7).
INSTANTIATE_TEST_SUITE_P(Weightings, Par2Acceptance,
                         ::testing::Values(SubspaceWeighting::n4sid, SubspaceWeighting::moesp, SubspaceWeighting::cva),
                         [](const auto& param_info) { return std::string(to_string(param_info.param)); });

}  // namespace test_acceptance_subspace_par2
