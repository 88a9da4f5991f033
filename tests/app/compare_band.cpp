// End-to-end: sysid compare --band prints, per input-output pair, the in-band
// coherence-weighted FRF error of the model against the data's H1 and the
// frequency of the worst mismatch: near zero for the true model, large for a wrong one.
#include <sysid/core/simulate.hpp>

#include <gtest/gtest.h>

#include "run_cli.hpp"

namespace test_app_compare_band {

using namespace sysid;
using namespace sysid::test;

namespace {

void write_log(const std::string& path, const StateSpace& plant, Eigen::Index n, std::uint64_t seed) {
  const Eigen::MatrixXd u = white_noise(n, 1, seed, 1.0);
  const Eigen::MatrixXd y = simulate(plant, u) + white_noise(n, 1, seed + 1, 0.05);
  Eigen::MatrixXd table(n, 3);
  table << Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * plant.Ts, u, y;
  write_csv(path, {"t", "u", "y"}, table);
}

/// The number after "y <- u: " in the band report.
double band_error(const std::string& out) { return number_after(out, "y <- u: "); }

}  // namespace

TEST(CompareBandApp, TrueModelNearZeroWrongModelLarge) {
  TempDir dir;
  const StateSpace plant = four_mode_plant();  // modes at 50 Hz (zeta 0.02) and 120 Hz, fs 1 kHz
  write_log(dir / "log.csv", plant, 100000, 11);
  write_model(dir / "true.json", plant);
  StateSpace wrong = modal_siso({{58.0, 0.02, 1.0}, {120.0, 0.05, 3.0}}, 0.001);
  write_model(dir / "wrong.json", wrong);

  const CliResult good = run_cli({"compare", dir / "true.json", dir / "log.csv", "--band", "0:200", "--nfft", "4096"});
  ASSERT_EQ(good.exit_code, 0) << describe(good);
  EXPECT_NE(good.out.find("in-band FRF error"), std::string::npos) << good.out;
  const CliResult bad = run_cli({"compare", dir / "wrong.json", dir / "log.csv", "--band", "0:200", "--nfft", "4096"});
  ASSERT_EQ(bad.exit_code, 0) << describe(bad);
  // True model: only the estimate's own random and resolution error (a few per cent,
  // see unit.validate.frequency_compare). Resonance 8 Hz (4 bandwidths) off: order 1.
  EXPECT_LT(band_error(good.out), 0.08) << good.out;
  EXPECT_GT(band_error(bad.out), 0.5) << bad.out;
  const double worst = number_after(bad.out, "worst mismatch at ");
  EXPECT_GT(worst, 45.0) << bad.out;
  EXPECT_LT(worst, 63.0) << bad.out;
  // The time-domain fit is still printed first.
  EXPECT_NE(good.out.find("fit [%]"), std::string::npos);
}

TEST(CompareBandApp, BadBand) {
  TempDir dir;
  const StateSpace plant = four_mode_plant();
  write_log(dir / "log.csv", plant, 4000, 3);
  write_model(dir / "m.json", plant);
  // Malformed band: usage error. A band above Nyquist has no frequency: bad input (2).
  EXPECT_EQ(run_cli({"compare", dir / "m.json", dir / "log.csv", "--band", "100"}).exit_code, 1);
  EXPECT_EQ(run_cli({"compare", dir / "m.json", dir / "log.csv", "--band", "200:100"}).exit_code, 1);
  const CliResult r = run_cli({"compare", dir / "m.json", dir / "log.csv", "--band", "600:700"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
}

}  // namespace test_app_compare_band
