// Acceptance of the model-family issue on the generated Par2-like family
// (data/family/generate_family.cpp: a flexible arm whose three in-band modes move
// with payload and stop position, 15 chirp logs with multisine validation logs):
// `sysid family` followed by checks against the true members.
//  - every member's in-band modes within 1 % in frequency, each mode one entry;
//  - the weight W: order <= 6, stable and minimum-phase, |W| >= its own bound at
//    every listed frequency, |W| >= the true bound (the true members' deviation
//    from the true model of the nominal chosen) at >= 98 % of a dense in-band grid,
//    median |W| / true bound <= 2;
//  - the nominal's true worst-case deviation within 1.5x of the best member's.
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/family/uncertainty_bound.hpp>
#include <sysid/io/family_file.hpp>
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "run_cli.hpp"

namespace test_acceptance_family_par2 {

using namespace sysid;

namespace {

const std::filesystem::path kFamilyDir = std::filesystem::path(SYSID_TEST_DATA_DIR) / "family";

/// modes_true.csv: member name -> frequencies of its modes, in mode order.
std::map<std::string, std::vector<double>> true_modes() {
  std::ifstream in(kFamilyDir / "modes_true.csv");
  std::string line;
  std::getline(in, line);
  std::map<std::string, std::vector<double>> out;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream s(line);
    for (std::string item; std::getline(s, item, ',');) f.push_back(item);
    out[f[0]].push_back(std::stod(f[4]));
  }
  return out;
}

std::string member_name(const FamilyFileMember& m) { return std::filesystem::path(m.log).stem().string(); }

struct Family {
  FamilyFile file;
  std::vector<StateSpace> truth;
};

const Family& family() {
  static const Family f = [] {
    test::TempDir dir;
    const std::string out = (dir.path() / "family.json").string();
    const test::CliResult r = test::run_cli({"family", (kFamilyDir / "manifest.csv").string(), "--inputs", "u", "--outputs",
                                             "y", "--method", "n4sid", "--order", "8", "--out", out});
    std::cout << r.out << r.err;
    if (r.exit_code != 0) throw std::runtime_error("sysid family failed: " + r.err);
    Family fam;
    fam.file = read_family_json(out);
    for (const FamilyFileMember& m : fam.file.members)
      fam.truth.push_back(read_model_json((kFamilyDir / "truth" / (member_name(m) + "_true.json")).string()).model);
    return fam;
  }();
  return f;
}

/// Worst-case (over the members and the grid) true deviation from member `nominal`.
double true_peak_deviation(const std::vector<std::vector<Eigen::MatrixXcd>>& frf, std::size_t nominal) {
  double peak = 0.0;
  for (std::size_t i = 0; i < frf.size(); ++i)
    for (std::size_t k = 0; k < frf[i].size(); ++k)
      peak = std::max(peak, deviation_from_nominal(frf[i][k], frf[nominal][k], UncertaintyForm::multiplicative_output));
  return peak;
}

}  // namespace

TEST(FamilyPar2, EveryInBandModeWithinOnePercentAndFollowedAsOneEntry) {
  const Family& f = family();
  const auto truth = true_modes();
  const double band_hi = f.file.uncertainty->band_hi_hz;
  // The true in-band modes (mode k of every member is one physical mode).
  std::size_t in_band = 0;
  for (double fk : truth.at(member_name(f.file.members.front())))
    if (fk <= band_hi) ++in_band;
  ASSERT_EQ(f.file.modes.size(), in_band) << "each true mode must be one entry, and nothing else";
  double worst = 0.0;
  for (std::size_t j = 0; j < in_band; ++j)
    for (std::size_t i = 0; i < f.file.members.size(); ++i) {
      const double estimated = f.file.modes[j].freq_hz(static_cast<Eigen::Index>(i));
      const double exact = truth.at(member_name(f.file.members[i]))[j];
      ASSERT_FALSE(std::isnan(estimated)) << "mode " << j + 1 << " absent in member " << i;
      worst = std::max(worst, std::abs(estimated / exact - 1.0));
      EXPECT_LT(std::abs(estimated / exact - 1.0), 0.01) << "mode " << j + 1 << ", member " << i;
    }
  std::cout << "largest relative frequency error over all members and modes: " << worst << "\n";
}

TEST(FamilyPar2, WeightCoversTheTrueBoundWithLittleConservatism) {
  const Family& f = family();
  ASSERT_TRUE(f.file.uncertainty.has_value());
  const FamilyFileUncertainty& u = *f.file.uncertainty;
  ASSERT_TRUE(u.weight.has_value());
  const StateSpace& w = u.weight->model;
  EXPECT_LE(w.order(), 6);
  EXPECT_LT(poles(w).cwiseAbs().maxCoeff(), 1.0);
  EXPECT_LT(transmission_zeros(w).cwiseAbs().maxCoeff(), 1.0);
  // Its own bound, at every listed frequency.
  const auto w_listed = frequency_response(w, u.frequency_hz);
  for (Eigen::Index k = 0; k < u.frequency_hz.size(); ++k)
    EXPECT_GE(std::abs(w_listed[static_cast<std::size_t>(k)](0, 0)), u.bound(k) * (1.0 - 1e-9)) << u.frequency_hz(k) << " Hz";
  // The true bound on a dense grid over the band.
  const double lo = std::max(u.band_lo_hz, u.band_hi_hz / 1000.0);
  const Eigen::Index points = 4000;
  Eigen::VectorXd grid(points);
  for (Eigen::Index k = 0; k < points; ++k) grid(k) = lo * std::pow(u.band_hi_hz / lo, static_cast<double>(k) / (points - 1));
  std::vector<std::vector<Eigen::MatrixXcd>> frf;
  for (const StateSpace& t : f.truth) frf.push_back(frequency_response(t, grid));
  const std::size_t nominal = static_cast<std::size_t>(*f.file.nominal_member);
  const auto w_dense = frequency_response(w, grid);
  Eigen::Index covered = 0;
  std::vector<double> ratio;
  for (Eigen::Index k = 0; k < points; ++k) {
    double true_bound = 0.0;
    for (std::size_t i = 0; i < frf.size(); ++i)
      true_bound = std::max(true_bound, deviation_from_nominal(frf[i][static_cast<std::size_t>(k)], frf[nominal][static_cast<std::size_t>(k)],
                                                               UncertaintyForm::multiplicative_output));
    const double magnitude = std::abs(w_dense[static_cast<std::size_t>(k)](0, 0));
    if (magnitude >= true_bound) ++covered;
    ratio.push_back(magnitude / true_bound);
  }
  std::nth_element(ratio.begin(), ratio.begin() + static_cast<long>(ratio.size() / 2), ratio.end());
  const double median_ratio = ratio[ratio.size() / 2];
  const double share = static_cast<double>(covered) / static_cast<double>(points);
  std::cout << "weight order " << w.order() << ": covers the true bound at " << 100.0 * share
            << " % of the dense grid; median |W| / true bound " << median_ratio << "\n";
  EXPECT_GE(share, 0.98);
  EXPECT_LE(median_ratio, 2.0);
}

TEST(FamilyPar2, NominalWorstCaseWithinOneAndAHalfOfTheBestMember) {
  const Family& f = family();
  const FamilyFileUncertainty& u = *f.file.uncertainty;
  std::vector<std::vector<Eigen::MatrixXcd>> frf;
  for (const StateSpace& t : f.truth) frf.push_back(frequency_response(t, u.frequency_hz));
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < frf.size(); ++c) best = std::min(best, true_peak_deviation(frf, c));
  const double chosen = true_peak_deviation(frf, static_cast<std::size_t>(*f.file.nominal_member));
  std::cout << "nominal member " << *f.file.nominal_member << ": true worst-case deviation " << chosen << ", best member's " << best
            << "\n";
  EXPECT_LE(chosen, 1.5 * best);
}

}  // namespace test_acceptance_family_par2
