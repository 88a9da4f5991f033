// End-to-end: sysid show on model files with known modes.
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>

#include <regex>

#include "random_systems.hpp"
#include "run_cli.hpp"

namespace test_app_show {

using namespace sysid;
using namespace sysid::test;

TEST(ShowApp, PrintsTheKnownModesAndTheFactoredTransferFunction) {
  TempDir dir;
  ModelFile f;
  f.model = four_mode_plant();  // 50 Hz / 0.02 and 120 Hz / 0.05 at 1 kHz
  Eigen::VectorXd sv(20);
  for (Eigen::Index k = 0; k < 20; ++k) sv(k) = std::pow(10.0, -0.3 * static_cast<double>(k));
  f.provenance = {{"method", "n4sid"}, {"order", 4}, {"singular_values", std::vector<double>(sv.data(), sv.data() + 20)}};
  write_model_json(dir / "m.json", f);

  const CliResult r = run_cli({"show", dir / "m.json"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("type: state-space"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("order: 4"), std::string::npos);
  EXPECT_NE(r.out.find("inputs (1): u"), std::string::npos);
  EXPECT_NE(r.out.find("outputs (1): y"), std::string::npos);
  EXPECT_NE(r.out.find("stability: stable"), std::string::npos);
  // Spectral radius = |z| of the 50 Hz pair = exp(-0.02 * 2 pi 50 * 0.001).
  EXPECT_NEAR(number_after(r.out, "spectral radius "), std::exp(-0.02 * 2 * std::numbers::pi * 50 * 0.001), 1e-5);

  // Modal table rows: "#  freq [Hz]  damping  pole  type". The model was built
  // from exactly these frequencies and dampings, so the table must print them
  // to its precision (6 significant digits for freq, 4 for damping).
  std::vector<std::pair<double, double>> modes;
  static const std::regex row(R"(\n\s+(\d+)\s+([\d.e+-]+)\s+([\d.e+-]+)\s+\S+ \+/- \S+j\s+pair)");
  for (auto it = std::sregex_iterator(r.out.begin(), r.out.end(), row); it != std::sregex_iterator(); ++it)
    modes.emplace_back(std::stod((*it)[2]), std::stod((*it)[3]));
  ASSERT_EQ(modes.size(), 2u) << r.out;
  EXPECT_NEAR(modes[0].first, 50.0, 1e-4);
  EXPECT_NEAR(modes[0].second, 0.02, 1e-6);
  EXPECT_NEAR(modes[1].first, 120.0, 1e-4);
  EXPECT_NEAR(modes[1].second, 0.05, 1e-6);

  // Factored transfer function: no zeros, two quadratic pole factors.
  EXPECT_NE(r.out.find("y <- u: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("/ [(z^2"), std::string::npos) << r.out;
  // Provenance, with the singular values shortened.
  EXPECT_NE(r.out.find("method: n4sid"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("... (20 values)"), std::string::npos) << r.out;
}

TEST(ShowApp, ManyChannelsAreCappedWithANote) {
  TempDir dir;
  StateSpace sys = random_modal_system(2, 4, 5, 9);
  sys.Ts = 0.01;
  write_model(dir / "mimo.json", sys);
  const CliResult r = run_cli({"show", dir / "mimo.json", "--digits", "6"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  std::size_t lines = 0;
  for (std::size_t pos = 0; (pos = r.out.find(" <- ", pos)) != std::string::npos; ++pos) ++lines;
  EXPECT_EQ(lines, 16u) << r.out;
  EXPECT_NE(r.out.find("4 more channels not shown"), std::string::npos) << r.out;
}

TEST(ShowApp, UnstableModelsAreFlagged) {
  TempDir dir;
  StateSpace sys(Eigen::MatrixXd::Constant(1, 1, 1.05), Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Ones(1, 1),
                 Eigen::MatrixXd::Zero(1, 1), 0.1);
  write_model(dir / "u.json", sys);
  const CliResult r = run_cli({"show", dir / "u.json"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("UNSTABLE (spectral radius 1.05"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("unstable"), std::string::npos) << r.out;  // the modal table's type column
}

TEST(ShowApp, HelpHasAnExample) {
  const CliResult r = run_cli({"show", "--help"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("sysid show model.json"), std::string::npos) << r.out;
}

}  // namespace test_app_show
