// End-to-end: --plot on frf, compare, show, n4sid and hsv writes a valid SVG (root
// element <svg> in the SVG namespace, closed) or PNG (signature and IHDR chunk)
// through gnuplot; without gnuplot the verbs still succeed and say how to get plots.
#include <sysid/core/simulate.hpp>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "run_cli.hpp"

namespace test_app_plot {

using namespace sysid;
using namespace sysid::test;

namespace {

bool have_gnuplot() {
  if (const char* env = std::getenv("SYSID_GNUPLOT")) return std::filesystem::exists(env);
  return std::system("command -v gnuplot >/dev/null 2>&1") == 0;
}

/// Skips XML declaration, comments, processing instructions and DOCTYPE; returns
/// the text of the root element's start tag ("svg width=..."), or "" if none.
std::string root_start_tag(const std::string& xml) {
  std::size_t pos = 0;
  for (;;) {
    pos = xml.find('<', pos);
    if (pos == std::string::npos) return {};
    if (xml.compare(pos, 4, "<!--") == 0) {
      pos = xml.find("-->", pos);
      if (pos == std::string::npos) return {};
      continue;
    }
    if (xml.compare(pos, 2, "<?") == 0 || xml.compare(pos, 2, "<!") == 0) {
      pos = xml.find('>', pos);
      if (pos == std::string::npos) return {};
      continue;
    }
    const std::size_t end = xml.find('>', pos);
    return end == std::string::npos ? std::string() : xml.substr(pos + 1, end - pos - 1);
  }
}

void expect_valid_svg(const std::string& path) {
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  const std::string text = read_text_file(path);
  const std::string root = root_start_tag(text);
  ASSERT_EQ(root.substr(0, 4), "svg ") << root;
  EXPECT_NE(root.find("xmlns=\"http://www.w3.org/2000/svg\""), std::string::npos) << root;
  const auto last = text.find_last_not_of(" \t\r\n");
  ASSERT_NE(last, std::string::npos);
  EXPECT_EQ(text.substr(text.rfind('<', last)), "</svg>" + text.substr(last + 1)) << "root element not closed";
  // Something was drawn: at least one path or polyline per curve set.
  EXPECT_NE(text.find("<path"), std::string::npos);
}

void expect_valid_png(const std::string& path) {
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  const std::string bytes = read_text_file(path);
  ASSERT_GT(bytes.size(), 33u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(bytes.substr(12, 4), "IHDR");
}

/// Log of the 4th-order app-test plant, white input, small output noise.
void write_plant_log(const std::string& path, Eigen::Index n) {
  const StateSpace plant = four_mode_plant();
  const Eigen::MatrixXd u = white_noise(n, 1, 4, 1.0);
  const Eigen::MatrixXd y = simulate(plant, u) + white_noise(n, 1, 5, 0.02);
  Eigen::MatrixXd table(n, 3);
  table << Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * plant.Ts, u, y;
  write_csv(path, {"t", "u", "y"}, table);
}

}  // namespace

TEST(PlotApp, EveryPlotKindIsAValidSvgOrPng) {
  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot not installed";
  TempDir dir;
  write_plant_log(dir / "log.csv", 6000);
  write_model(dir / "m.json", four_mode_plant());

  CliResult r = run_cli({"frf", dir / "log.csv", "--inputs", "u", "--outputs", "y", "--nfft", "512", "--out", dir / "frf.csv",
                         "--plot", dir / "frf.svg"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_valid_svg(dir / "frf.svg");

  r = run_cli({"compare", dir / "m.json", dir / "log.csv", "--band", "1:300", "--nfft", "512", "--plot", dir / "compare.svg"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_valid_svg(dir / "compare.svg");

  r = run_cli({"show", dir / "m.json", "--plot", dir / "show.svg"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_valid_svg(dir / "show.svg");

  r = run_cli({"n4sid", dir / "log.csv", "--inputs", "u", "--outputs", "y", "--order", "4", "--plot", dir / "sv.svg"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_valid_svg(dir / "sv.svg");

  r = run_cli({"n4sid", dir / "log.csv", "--inputs", "u", "--outputs", "y", "--order", "2:16", "--stabilization",
               dir / "stab.svg"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_valid_svg(dir / "stab.svg");
  EXPECT_NE(read_text_file(dir / "stab.svg").find("physical modes"), std::string::npos);

  r = run_cli({"hsv", dir / "m.json", "--plot", dir / "hsv.svg"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_valid_svg(dir / "hsv.svg");
  for (const std::string level : {"0.4 %", ">2 %<"})
    EXPECT_NE(read_text_file(dir / "hsv.svg").find(level), std::string::npos) << level << " is not marked";

  r = run_cli({"show", dir / "m.json", "--plot", dir / "show.png"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_valid_png(dir / "show.png");
}

TEST(PlotApp, WithoutGnuplotTheVerbSucceedsAndSaysHowToGetPlots) {
  TempDir dir;
  write_plant_log(dir / "log.csv", 3000);
  const char* old = std::getenv("SYSID_GNUPLOT");
  const std::string saved = old ? old : "";
  ::setenv("SYSID_GNUPLOT", (dir / "no-such-gnuplot").c_str(), 1);
  const CliResult r = run_cli({"frf", dir / "log.csv", "--inputs", "u", "--outputs", "y", "--nfft", "256", "--out", dir / "frf.csv",
                               "--plot", dir / "frf.svg"});
  if (old) ::setenv("SYSID_GNUPLOT", saved.c_str(), 1);
  else ::unsetenv("SYSID_GNUPLOT");
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(std::filesystem::exists(dir / "frf.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "frf.svg"));
  EXPECT_NE(r.err.find("gnuplot"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("apt-get install gnuplot"), std::string::npos) << r.err;
}

}  // namespace test_app_plot
