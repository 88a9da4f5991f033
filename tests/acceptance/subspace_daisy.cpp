// n4sid with an automatic order on every input/output set of the DaISy
// collection in ../shared/data/real (its README lists them): a user's first
// command on a classic benchmark must give a model or a clear reason, never a
// silent failure. Estimation on the first half, validation on the second (the
// SLICOT demos' convention; DaISy has no official split).
//
// Before 2026-11-24 the glass furnace (6 outputs, 3 inputs) and the power plant
// (3 outputs, 5 inputs, 200 samples) stopped with "the singular values show no
// dynamics": Bauer's SVC penalty per order exceeded every drop of their
// canonical correlations (0.9999, 0.9987, ...). n4sid now tests those
// correlations (Bartlett) and falls back to the singular-value gap, with a warning.
#include <sysid/core/errors.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/subspace/n4sid.hpp>
#include <sysid/validate/compare.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

namespace test_acceptance_subspace_daisy {

namespace {

const std::string kReal = std::string(SYSID_SOURCE_DIR) + "/../shared/data/real/";

struct DaisySet {
  std::string folder, file;
  std::vector<std::string> inputs, outputs;
  bool time_column;  // else unit sample time (DaISy gives none)
};

std::vector<std::string> names(const std::string& prefix, int count) {
  std::vector<std::string> v;
  for (int k = 1; k <= count; ++k) v.push_back(prefix + std::to_string(k));
  return v;
}

struct Identified {
  sysid::N4sidResult result;
  Eigen::VectorXd validation_fit;
};

Identified identify_first_half(const DaisySet& set) {
  sysid::LogOptions o;
  o.inputs = set.inputs;
  o.outputs = set.outputs;
  if (!set.time_column) {
    o.time_column.clear();
    o.ts = 1.0;
  }
  const sysid::IoData data = sysid::read_log(kReal + set.folder + "/" + set.file, o);
  const sysid::DataSplit halves = sysid::split(data, 0.5);
  Identified out;
  out.result = sysid::n4sid(halves.estimation, {});
  sysid::CompareOptions co;
  co.input_offset = out.result.input_offset;
  co.output_offset = out.result.output_offset;
  out.validation_fit = sysid::compare(out.result.model, out.result.K, halves.validation.experiments.front(), co).fit_percent;
  return out;
}

}  // namespace

TEST(SubspaceDaisy, AutomaticOrderGivesAModelOnEverySet) {
  if (!std::filesystem::exists(kReal + "daisy_robot_arm")) GTEST_SKIP() << "no " << kReal;
  const std::vector<DaisySet> sets = {
      {"daisy_robot_arm", "robot_arm.csv", {"u"}, {"y"}, false},
      {"daisy_cd_player_arm", "cd_player_arm.csv", names("u", 2), names("y", 2), false},
      {"daisy_flutter", "flutter.csv", {"u"}, {"y"}, false},
      {"daisy_hair_dryer", "dryer.csv", {"u"}, {"y"}, true},
      {"daisy_ball_beam", "ballbeam.csv", {"u"}, {"y"}, true},
      {"daisy_heat_exchanger", "exchanger.csv", {"u"}, {"y"}, true},
      {"daisy_glass_furnace", "glassfurnace.csv", names("u", 3), names("y", 6), false},
      {"daisy_power_plant", "powerplant.csv", names("u", 5), names("y", 3), true},
      {"daisy_evaporator", "evaporator.csv", names("u", 3), names("y", 3), false},
      {"daisy_winding", "winding.csv", names("u", 5), names("y", 2), true},
      {"daisy_industrial_dryer", "dryer2.csv", names("u", 3), names("y", 3), true},
      {"daisy_thermic_wall", "thermic_res_wall.csv", names("u", 2), {"y"}, false},
      {"daisy_heating_system", "heating_system.csv", {"u"}, {"y"}, true},
  };
  for (const DaisySet& set : sets) {
    SCOPED_TRACE(set.folder);
    if (!std::filesystem::exists(kReal + set.folder + "/" + set.file)) {
      ADD_FAILURE() << "missing " << set.folder << "/" << set.file;
      continue;
    }
    Identified id;
    ASSERT_NO_THROW(id = identify_first_half(set));
    EXPECT_GE(id.result.order, 1);
    EXPECT_TRUE(id.validation_fit.allFinite());
    std::cout << set.folder << ": order " << id.result.order << ", validation fit " << id.validation_fit.transpose() << "\n";
  }
}

TEST(SubspaceDaisy, SwampedSvcOnTheGlassFurnaceAndThePowerPlant) {
  // Six (three) outputs and 600 (100) samples per half: SVC's penalty exceeds
  // every drop of the squared correlations, and the canonical-correlation test
  // chooses (subspace/order_selection.hpp). On the glass furnace its order (9,
  // 2026-11-28) predicts the second half at 54.0 % mean fit, where the gap rule's
  // former order 1 gave 27-53 %: the bound is a few points under today's result.
  if (!std::filesystem::exists(kReal + "daisy_glass_furnace")) GTEST_SKIP() << "no " << kReal;
  for (const DaisySet& set : {DaisySet{"daisy_glass_furnace", "glassfurnace.csv", names("u", 3), names("y", 6), false},
                              DaisySet{"daisy_power_plant", "powerplant.csv", names("u", 5), names("y", 3), true}}) {
    SCOPED_TRACE(set.folder);
    const Identified id = identify_first_half(set);
    EXPECT_NE(id.result.order_rule.find("canonical-correlation test"), std::string::npos) << id.result.order_rule;
    EXPECT_NE(id.result.order_rule.find("SVC (n = 0) is swamped"), std::string::npos) << id.result.order_rule;
    if (set.folder == "daisy_glass_furnace") {
      EXPECT_GT(id.validation_fit.mean(), 50.0);
    }
  }
}

TEST(SubspaceDaisy, WellExcitedSetsPredictTheirSecondHalf) {
  // Regression bounds a few points under today's results (robot arm 96.9 %,
  // hair dryer 85.8 %, 2026-11-24): sets whose input excites the dynamics in
  // both halves, unlike the flutter record (README: non-stationary input).
  if (!std::filesystem::exists(kReal + "daisy_robot_arm")) GTEST_SKIP() << "no " << kReal;
  EXPECT_GT(identify_first_half({"daisy_robot_arm", "robot_arm.csv", {"u"}, {"y"}, false}).validation_fit(0), 94.0);
  EXPECT_GT(identify_first_half({"daisy_hair_dryer", "dryer.csv", {"u"}, {"y"}, true}).validation_fit(0), 82.0);
}

}  // namespace test_acceptance_subspace_daisy
