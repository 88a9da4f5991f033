// Tests for augmented models in model files and the diagnose report JSON
// (include/sysid/io/augmented_model_file.hpp, DESIGN.md "diagnose: the report
// contract"): exact round trip through the JSON text, channels by name, the
// errors a hand-edited file can contain, and the report's keys and units.
#include <sysid/diagnose/augmented_model.hpp>
#include <sysid/diagnose/diagnose.hpp>
#include <sysid/io/augmented_model_file.hpp>
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <set>
#include <string>

#include <sysid/core/errors.hpp>
#include <sysid/core/math_constants.hpp>

#include "../support/diagnose_cases.hpp"

namespace test_unit_io_augmented_model_file {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using nlohmann::json;
using sysid::AugmentedModel;
using sysid::PhysicsBlock;
using sysid::StateSpace;

constexpr double kTs = 1e-3;
using sysid::kTwoPi;

/// Discrete real-modal model, one 2x2 rotation block r R(th) per mode with
/// z = exp(s Ts): poles exactly at (freq, damping), so a continuous equivalent
/// exists (substeps > 1 are usable). Mode k is driven by input k % m and seen by
/// every output with weights that differ per output.
StateSpace modal(const std::vector<std::pair<double, double>>& modes, Eigen::Index m, Eigen::Index l) {
  const auto n = static_cast<Eigen::Index>(2 * modes.size());
  MatrixXd A = MatrixXd::Zero(n, n), B = MatrixXd::Zero(n, m), C = MatrixXd::Zero(l, n);
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(2 * k);
    const double w = kTwoPi * modes[k].first, zeta = modes[k].second;
    const double r = std::exp(-zeta * w * kTs), th = w * std::sqrt(1.0 - zeta * zeta) * kTs;
    A.block(i, i, 2, 2) << r * std::cos(th), r * std::sin(th), -r * std::sin(th), r * std::cos(th);
    B(i + 1, static_cast<Eigen::Index>(k) % m) = 1.0;
    for (Eigen::Index o = 0; o < l; ++o) C(o, i) = 1.0 / (1.0 + static_cast<double>(o + k));
  }
  return StateSpace(A, B, C, MatrixXd::Zero(l, m), kTs);
}

using sysid::test::physics_block;

/// A value with a full 53-bit mantissa in [lo, hi): a round trip through text
/// with fewer than 17 significant digits would change it.
double awkward(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

/// A 2-input 2-output model holding every kind of block (every parameter set),
/// with offsets, an initial state and substeps > 1.
AugmentedModel every_kind_model() {
  std::mt19937_64 rng(20261122);
  AugmentedModel a;
  a.nominal = modal({{40.0, 0.03}, {95.0, 0.05}, {160.0, 0.02}}, 2, 2);
  a.nominal.input_names = {"force", "torque"};
  a.nominal.output_names = {"pos", "angle"};
  a.x0 = VectorXd::NullaryExpr(6, [&] { return awkward(rng, -1e-3, 1e-3); });
  a.input_offset = VectorXd{{awkward(rng, 0.1, 0.2), awkward(rng, -0.2, -0.1)}};
  a.output_offset = VectorXd{{awkward(rng, 1.0, 2.0), awkward(rng, -3.0, -2.0)}};
  a.substeps = 3;
  const auto p = [&](double lo, double hi) { return awkward(rng, lo, hi); };
  a.blocks = {
      physics_block("missing_mode", {{"freq_hz", p(200, 250)}, {"damping", p(0.01, 0.02)}, {"static_gain", p(0.1, 0.2)},
                             {"velocity_gain", p(0.01, 0.02)}}, 1, 0),
      physics_block("time_delay", {{"delay_s", p(1.2e-3, 1.8e-3)}}, 0, 0),
      physics_block("gain_error", {{"ratio", p(1.05, 1.1)}}, 0, 1),
      physics_block("input_lag", {{"corner_hz", p(80, 120)}}, 1, 1),
      physics_block("coulomb_friction", {{"level", p(0.01, 0.02)}, {"velocity_scale", p(0.5, 1.0)}, {"asymmetry", p(-0.005, 0.005)}}, 0, 0),
      physics_block("backlash", {{"width", p(0.05, 0.1)}}, 1, 0),
      physics_block("deadzone", {{"width", p(0.05, 0.1)}}, 0, 0),
      physics_block("saturation", {{"limit", p(1.5, 2.0)}, {"storage_pole", p(0.9, 0.95)}, {"spill", p(0.2, 0.5)}}, 1, 1),
      physics_block("cubic_stiffness", {{"coefficient", p(1e-3, 2e-3)}, {"linear_coefficient", p(-1e-3, 1e-3)}}, 1, 1),
      physics_block("hysteresis", {{"alpha", p(0.1, 0.2)}, {"beta", p(0.2, 0.4)}, {"gamma", p(0.1, 0.2)}}, 0, 0),
      physics_block("periodic_disturbance", {{"freq_hz", p(49, 51)}, {"amplitude", p(0.01, 0.02)}, {"phase_rad", p(-3, 3)}}, 0, 1),
      physics_block("offset_drift", {{"offset", p(-0.1, 0.1)}, {"slope", p(-0.01, 0.01)}}, 0, 0),
      physics_block("cross_coupling", {{"gain", p(0.1, 0.3)}}, 1, 0),
      physics_block("mode_shift", {{"freq_hz", p(96, 98)}, {"damping", p(0.04, 0.06)}, {"nominal_freq_hz", 95.0},
                                   {"nominal_damping", 0.05}, {"numerator_b0", p(1e4, 2e4)}, {"numerator_b1", p(-5, 5)}}, 0, 1),
      physics_block("constant_force", {{"force", p(-0.02, -0.01)}}, 1, 1),
  };
  // The second output read as a velocity: its forces act from its integral.
  a.output_quantities = {sysid::OutputQuantity::position, sysid::OutputQuantity::velocity};
  return a;
}

MatrixXd test_input(Eigen::Index rows, Eigen::Index cols, std::uint64_t seed, double sigma) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  return MatrixXd::NullaryExpr(rows, cols, [&] { return g(rng); });
}

/// augmented -> file -> text -> file -> augmented.
AugmentedModel through_text(const AugmentedModel& a) {
  const std::string text = sysid::model_to_json_string(sysid::augmented_model_to_file(a));
  return sysid::augmented_model_from_file(sysid::model_from_json_string(text, "aug.json"), "aug.json");
}

/// The JSON text of a 1-input 1-output model with three blocks, for editing.
json three_block_json() {
  AugmentedModel a;
  a.nominal = modal({{40.0, 0.03}}, 1, 1);
  a.nominal.input_names = {"u"};
  a.nominal.output_names = {"y"};
  a.blocks = {physics_block("time_delay", {{"delay_s", 2e-3}}), physics_block("gain_error", {{"ratio", 1.1}}),
              physics_block("deadzone", {{"width", 0.2}})};
  return json::parse(sysid::model_to_json_string(sysid::augmented_model_to_file(a)));
}

/// The DataError message of reading `j` as "aug.json" (fails the test if none).
std::string read_error(const json& j) {
  try {
    (void)sysid::augmented_model_from_file(sysid::model_from_json_string(j.dump(2), "aug.json"), "aug.json");
  } catch (const sysid::DataError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no DataError for " << j.dump();
  return {};
}

void expect_contains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "'" << part << "' not in: " << text;
}

}  // namespace

TEST(AugmentedModelFile, EveryKindRoundTripsBitExactAndSimulatesIdentically) {
  const AugmentedModel a = every_kind_model();
  ASSERT_EQ(a.blocks.size(), sysid::block_kinds().size());  // every kind is exercised
  for (const auto& b : a.blocks) ASSERT_EQ(b.params.size(), b.info().parameters.size()) << b.kind;
  EXPECT_EQ(sysid::augmented_model_to_file(a).type, "augmented");

  const AugmentedModel r = through_text(a);
  ASSERT_EQ(r.blocks.size(), a.blocks.size());
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    SCOPED_TRACE(a.blocks[k].kind);
    EXPECT_EQ(r.blocks[k].kind, a.blocks[k].kind);
    EXPECT_EQ(r.blocks[k].input, a.blocks[k].input);
    EXPECT_EQ(r.blocks[k].output, a.blocks[k].output);
    // 17 significant digits: every double comes back identical (== on the maps
    // compares the names and the values bit for bit).
    EXPECT_EQ(r.blocks[k].params, a.blocks[k].params);
  }
  EXPECT_EQ(r.substeps, a.substeps);
  EXPECT_EQ(r.x0, a.x0);
  EXPECT_EQ(r.input_offset, a.input_offset);
  EXPECT_EQ(r.output_offset, a.output_offset);
  EXPECT_EQ(r.output_quantities, a.output_quantities);

  // Same model, same arithmetic: the simulations agree to the last bit.
  const MatrixXd u = test_input(1500, 2, 7, 0.5);
  const MatrixXd y0 = sysid::simulate_augmented(a, u), y1 = sysid::simulate_augmented(r, u);
  ASSERT_TRUE(y0.allFinite());
  EXPECT_GT(y0.cwiseAbs().maxCoeff(), 1e-3);  // the comparison is not between zeros
  EXPECT_EQ((y0 - y1).cwiseAbs().maxCoeff(), 0.0);
}

TEST(AugmentedModelFile, BlocksReferToChannelsByName) {
  AugmentedModel a;
  a.nominal = modal({{40.0, 0.03}, {95.0, 0.05}}, 2, 2);
  a.nominal.input_names = {"force", "torque"};
  a.nominal.output_names = {"pos", "angle"};
  a.blocks = {physics_block("deadzone", {{"width", 0.1}}, 1, 0), physics_block("gain_error", {{"ratio", 0.9}}, 0, 1)};
  const json j = json::parse(sysid::model_to_json_string(sysid::augmented_model_to_file(a)));
  ASSERT_TRUE(j.contains("blocks")) << j.dump(2);
  EXPECT_EQ(j["blocks"][0]["input"], "torque");
  EXPECT_EQ(j["blocks"][0]["output"], "pos");
  EXPECT_EQ(j["blocks"][0]["connection"], "actuator");
  EXPECT_EQ(j["blocks"][1]["input"], "force");
  EXPECT_EQ(j["blocks"][1]["output"], "angle");
  EXPECT_EQ(j["blocks"][1]["connection"], "sensor");

  // A hand edit moving the dead zone to the other input is read by name.
  json edited = j;
  edited["blocks"][0]["input"] = "force";
  edited["blocks"][1]["output"] = "pos";
  const AugmentedModel r = sysid::augmented_model_from_file(sysid::model_from_json_string(edited.dump(), "e.json"), "e.json");
  ASSERT_EQ(r.blocks.size(), 2u);
  EXPECT_EQ(r.blocks[0].input, 0);
  EXPECT_EQ(r.blocks[0].output, 0);
  EXPECT_EQ(r.blocks[1].input, 0);
  EXPECT_EQ(r.blocks[1].output, 0);

  // Without channel names the defaults u1.., y1.. are used both ways.
  a.nominal.input_names.clear();
  a.nominal.output_names.clear();
  const json d = json::parse(sysid::model_to_json_string(sysid::augmented_model_to_file(a)));
  EXPECT_EQ(d["blocks"][0]["input"], "u2");
  EXPECT_EQ(d["blocks"][1]["output"], "y2");
  const AugmentedModel rd = through_text(a);
  EXPECT_EQ(rd.blocks[0].input, 1);
  EXPECT_EQ(rd.blocks[1].output, 1);
}

TEST(AugmentedModelFile, NoBlocksIsAPlainStateSpaceFile) {
  AugmentedModel a;
  a.nominal = modal({{40.0, 0.03}}, 1, 1);
  const sysid::ModelFile f = sysid::augmented_model_to_file(a);
  EXPECT_EQ(f.type, "state-space");
  const json j = json::parse(sysid::model_to_json_string(f));
  EXPECT_EQ(j.value("type", "state-space"), "state-space");
  EXPECT_FALSE(j.contains("blocks"));
  EXPECT_FALSE(j.contains("nominal"));
  EXPECT_TRUE(j.contains("A"));
  // And a state-space file reads back as the model with no blocks.
  const AugmentedModel r = through_text(a);
  EXPECT_TRUE(r.blocks.empty());
  EXPECT_EQ(r.nominal.A, a.nominal.A);
}

TEST(AugmentedModelFile, SaturationWithoutTheLaterParametersIsAnAmplifier) {
  // Files written before a saturation had a store (storage_pole, spill) keep
  // their meaning: clipping at +-limit.
  json j = three_block_json();
  j["blocks"][2] = {{"kind", "saturation"}, {"input", "u"}, {"output", "y"}, {"params", {{"limit", 0.7}}}};
  const AugmentedModel a = sysid::augmented_model_from_file(sysid::model_from_json_string(j.dump(2), "aug.json"), "aug.json");
  ASSERT_EQ(a.blocks.size(), 3u);
  EXPECT_EQ(a.blocks[2].param("limit"), 0.7);
  EXPECT_EQ(a.blocks[2].param("storage_pole"), 0.0);
  EXPECT_EQ(a.blocks[2].param("spill"), 0.0);
  const MatrixXd u = test_input(50, 1, 5, 1.0);
  const MatrixXd w = sysid::actuator_output({a.blocks[2]}, u, a.nominal.Ts, u.rows());
  EXPECT_TRUE(w.isApprox(u.cwiseMax(-0.7).cwiseMin(0.7)));
}

TEST(AugmentedModelFile, ErrorsNameTheBlockAndTheProblem) {
  {
    json j = three_block_json();
    j["blocks"][1]["kind"] = "warp_drive";
    const std::string m = read_error(j);
    expect_contains(m, "aug.json");
    expect_contains(m, "blocks[1]");
    expect_contains(m, "warp_drive");
  }
  {
    json j = three_block_json();
    j["blocks"][2]["params"].erase("width");
    const std::string m = read_error(j);
    expect_contains(m, "aug.json");
    expect_contains(m, "blocks[2]");
    expect_contains(m, "missing 'width'");
  }
  {
    json j = three_block_json();
    j["blocks"][1]["params"]["ratio"] = "1.1";
    const std::string m = read_error(j);
    expect_contains(m, "blocks[1]");
    expect_contains(m, "ratio");
    expect_contains(m, "number");
  }
  {
    json j = three_block_json();
    j["blocks"][2]["input"] = "nosuch";
    const std::string m = read_error(j);
    expect_contains(m, "blocks[2]");
    expect_contains(m, "'nosuch'");
  }
  {
    // A value of the right type but outside what the simulation admits.
    json j = three_block_json();
    j["blocks"][2]["params"]["width"] = -0.5;
    const std::string m = read_error(j);
    expect_contains(m, "aug.json");
    expect_contains(m, "width");
    expect_contains(m, "blocks[2]");
  }
  {
    json j = three_block_json();
    j["substeps"] = 0;
    const std::string m = read_error(j);
    expect_contains(m, "aug.json");
    expect_contains(m, "substeps");
  }
}

TEST(AugmentedModelFile, OutputQuantitiesAreCheckedAgainstTheOutputs) {
  {
    json j = three_block_json();
    j["output_quantities"] = {"position", "velocity"};  // the model has one output
    expect_contains(read_error(j), "output_quantities: expected a list of");
  }
  {
    json j = three_block_json();
    j["output_quantities"] = {"speed"};
    const std::string m = read_error(j);
    expect_contains(m, "output_quantities[0]");
    expect_contains(m, "'speed'");
  }
}

TEST(AugmentedModelFile, RepeatedChannelNameIsAmbiguous) {
  // Model files may repeat a channel name; a block naming it used to act silently
  // on the first such channel, so a block written for the second one came back
  // on the first.
  AugmentedModel a;
  a.nominal = modal({{40.0, 0.03}, {95.0, 0.05}}, 2, 2);
  a.nominal.input_names = {"u", "u"};
  a.nominal.output_names = {"y1", "y2"};
  a.blocks = {physics_block("deadzone", {{"width", 0.1}}, 1, 0)};
  const json j = json::parse(sysid::model_to_json_string(sysid::augmented_model_to_file(a)));
  const std::string m = read_error(j);
  expect_contains(m, "blocks[0].input");
  expect_contains(m, "'u' is ambiguous");
  expect_contains(m, "channels 1 and 2");
  // The outputs are distinct: naming one of them is fine.
  json outputs_only = j;
  outputs_only["blocks"][0].erase("input");
  EXPECT_EQ(sysid::augmented_model_from_file(sysid::model_from_json_string(outputs_only.dump(), "aug.json"), "aug.json")
                .blocks.at(0)
                .output,
            0);
}

TEST(AugmentedModelFile, ReportHasTheDesignKeysAndUnits) {
  // A 2nd-order plant (mode at 60 Hz, zeta 0.04) whose sensor reads 10 % high.
  AugmentedModel nominal;
  nominal.nominal = modal({{60.0, 0.04}}, 1, 1);
  nominal.nominal.input_names = {"u"};
  nominal.nominal.output_names = {"y"};
  const Eigen::Index N = 4000;
  const MatrixXd u = test_input(N, 1, 11, 1.0);
  const sysid::AugmentedSimulator truth(nominal.nominal);
  MatrixXd y = truth.simulate({physics_block("gain_error", {{"ratio", 1.1}})}, u);
  const double rms = std::sqrt(y.squaredNorm() / static_cast<double>(N));
  y += test_input(N, 1, 12, 0.01 * rms);  // 1 % noise

  const sysid::DiagnoseReport report = sysid::diagnose(nominal, u, y);
  const json j = sysid::diagnose_report_to_json(report, kTs);

  for (const char* key : {"fit_before", "fit_after", "validation", "findings"}) ASSERT_TRUE(j.contains(key)) << key;
  EXPECT_TRUE(j["fit_before"].is_number());
  EXPECT_TRUE(j["fit_after"].is_number());
  EXPECT_TRUE(j["validation"].is_string());
  ASSERT_TRUE(j["findings"].is_array());
  ASSERT_FALSE(j["findings"].empty()) << j.dump(2);
  // Gain 1.1 with 1 % noise: the nominal fits about 100 (1 - 0.1/1.1) = 91 %, the
  // corrected model about 99 % (the noise floor).
  EXPECT_GT(j["fit_after"].get<double>() - j["fit_before"].get<double>(), 5.0);

  // model_params and parameter_evidence: documented extensions; uncertainty: DESIGN.md.
  const std::set<std::string> finding_keys{"kind",    "params",       "fit_before", "fit_after",          "location",
                                           "evidence", "summary",     "model_params", "parameter_evidence", "uncertainty"};
  const std::set<std::string> location_keys{"freq_hz", "time_s", "input", "output"};
  for (const auto& f : j["findings"]) {
    std::set<std::string> keys;
    for (const auto& [k, v] : f.items()) keys.insert(k);
    EXPECT_EQ(keys, finding_keys) << f.dump(2);
    std::set<std::string> loc;
    for (const auto& [k, v] : f["location"].items()) loc.insert(k);
    EXPECT_EQ(loc, location_keys) << f.dump(2);
    EXPECT_TRUE(f["location"]["freq_hz"].is_null() || (f["location"]["freq_hz"].is_array() && f["location"]["freq_hz"].size() == 2));
    EXPECT_TRUE(f["location"]["time_s"].is_null() || f["location"]["time_s"].is_array());
    EXPECT_EQ(f["location"]["input"], "u");
    EXPECT_EQ(f["location"]["output"], "y");
    EXPECT_TRUE(f["summary"].is_string() && !f["summary"].get<std::string>().empty());
    EXPECT_TRUE(f["fit_before"].is_number() && f["fit_after"].is_number());
    // params: exactly the DESIGN.md reported names of the kind.
    const auto& info = sysid::block_kind_info(f["kind"].get<std::string>());
    std::set<std::string> reported(info.reported.begin(), info.reported.end()), got;
    for (const auto& [k, v] : f["params"].items()) {
      got.insert(k);
      EXPECT_TRUE(v.is_number()) << k;
    }
    EXPECT_EQ(got, reported) << f.dump(2);
    // uncertainty: a standard error per reported parameter (DESIGN.md).
    std::set<std::string> with_error;
    for (const auto& [k, v] : f["uncertainty"].items()) {
      with_error.insert(k);
      EXPECT_TRUE(v.is_number() && v.get<double>() >= 0.0) << k;
    }
    EXPECT_EQ(with_error, reported) << f.dump(2);
  }
  const json& first = j["findings"][0];
  ASSERT_EQ(first["kind"], "gain_error") << j.dump(2);
  // measured / nominal, not a percentage: the least-squares ratio on 4000
  // samples at 1 % noise is within ~1e-3 of 1.1; 2 % leaves room for the fit's
  // tolerance and a unit mistake (110 or 0.1) cannot pass.
  EXPECT_NEAR(first["params"]["ratio"].get<double>(), 1.1, 0.022);
  // Its standard error at 1 % noise on 4000 samples is of order 1e-4: small, not zero.
  EXPECT_GT(first["uncertainty"]["ratio"].get<double>(), 0.0);
  EXPECT_LT(first["uncertainty"]["ratio"].get<double>(), 0.01);
  EXPECT_TRUE(j["closed_loop"].is_object() && j["closed_loop"]["detected"].is_boolean());
  EXPECT_TRUE(j["output_quantities"].is_object());
}

}  // namespace test_unit_io_augmented_model_file
