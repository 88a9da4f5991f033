// Tests for the family file (include/sysid/io/family_file.hpp): what is written
// reads back (models bit-exactly, conditions as numbers or labels, NaN as null,
// the nominal with and without a member, the uncertainty with and without a
// weight), every model object inside is a model file's object, and bad files are
// refused naming the key.
#include <sysid/core/errors.hpp>
#include <sysid/io/family_file.hpp>
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <variant>

#include "random_systems.hpp"
#include "run_cli.hpp"

namespace test_unit_io_family_file {

using namespace sysid;
using sysid::test::TempDir;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// A model with modes at `f` Hz at 1 kHz, 1 input "u", 2 outputs "y1" "y2".
ModelFile member_model(const std::vector<double>& f, std::uint64_t seed) {
  ModelFile m;
  m.model = sysid::test::rotated_modal_system(f, std::vector<double>(f.size(), 0.02), 1, 2, seed, 0.001);
  m.model.input_names = {"u"};
  m.model.output_names = {"y1", "y2"};
  m.provenance = {{"method", "n4sid"}, {"order", m.model.order()}};
  return m;
}

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
  Eigen::Index k = 0;
  for (double x : v) out(k++) = x;
  return out;
}

/// Three members (orders 4, 6, 4), two conditions, two modes, a weight.
FamilyFile sample_family() {
  FamilyFile f;
  f.Ts = 0.001;
  f.inputs = {"u"};
  f.outputs = {"y1", "y2"};
  f.condition_names = {"payload_kg", "side"};
  const std::vector<std::vector<double>> freqs = {{28.4, 61.0}, {27.9, 60.2, 140.0}, {27.1, 59.0}};
  const std::vector<ConditionValue> payload = {0.0, 0.5, 1.25};
  const std::vector<ConditionValue> side = {std::string("Pos1"), std::string("Pos 2, \"left\""), std::string("Pos1")};
  for (std::size_t k = 0; k < 3; ++k) {
    FamilyFileMember m;
    m.conditions = {payload[k], side[k]};
    m.log = "runs/m" + std::to_string(k) + ".csv";
    if (k == 1) m.validate = "runs/v1.csv";
    m.model = member_model(freqs[k], 10 + k);
    m.fit_percent = k == 2 ? vec({91.5, kNaN}) : vec({93.1, 88.25 + static_cast<double>(k)});
    f.members.push_back(std::move(m));
  }
  TrackedMode a, b;
  a.freq_hz = vec({28.4, 27.9, 27.1});
  a.damping = vec({0.021, 0.024, 0.026});
  b.freq_hz = vec({61.0, kNaN, 59.0});
  b.damping = vec({0.03, kNaN, 0.031});
  f.modes = {a, b};
  f.nominal_member = 1;
  f.nominal_criterion = "the member whose bound has the smallest peak over the band";
  f.nominal_model = f.members[1].model;
  FamilyFileUncertainty u;
  u.form = "multiplicative-output";
  u.band_lo_hz = 0.5;
  u.band_hi_hz = 100.0;
  u.frequency_hz = Eigen::VectorXd::LinSpaced(7, 0.5, 100.0);
  u.bound = vec({0.1, 0.12, 0.5, 2.25, 0.3, 0.2, 0.1 / 3.0});
  u.allowance = "per member, 2.15 x ...";
  ModelFile w;
  w.model = StateSpace(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Constant(1, 1, 0.25),
                       Eigen::MatrixXd::Constant(1, 1, 0.75), 0.001);
  u.weight = w;
  u.weight_fit = {{"order", 1}, {"median_conservatism", 1.5}};
  f.uncertainty = u;
  return f;
}

void expect_same_model(const ModelFile& a, const ModelFile& b, const std::string& what) {
  EXPECT_EQ(a.model.A, b.model.A) << what;
  EXPECT_EQ(a.model.B, b.model.B) << what;
  EXPECT_EQ(a.model.C, b.model.C) << what;
  EXPECT_EQ(a.model.D, b.model.D) << what;
  EXPECT_EQ(a.model.Ts, b.model.Ts) << what;
  EXPECT_EQ(a.model.input_names, b.model.input_names) << what;
  EXPECT_EQ(a.model.output_names, b.model.output_names) << what;
}

/// Both NaN or equal.
void expect_same_values(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (Eigen::Index k = 0; k < a.size(); ++k) {
    if (std::isnan(b(k)))
      EXPECT_TRUE(std::isnan(a(k))) << what << "[" << k << "]";
    else
      EXPECT_EQ(a(k), b(k)) << what << "[" << k << "]";
  }
}

/// The DataError's text for `text` read as a family file named "fam.json".
std::string error_text(const std::string& text) {
  try {
    family_from_json_string(text, "fam.json");
  } catch (const DataError& e) {
    EXPECT_EQ(e.file(), "fam.json") << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no DataError";
  return {};
}

/// The sample family as JSON, changed by `edit`, as text.
template <class Edit>
std::string edited(Edit edit) {
  nlohmann::json j = nlohmann::json::parse(family_to_json_string(sample_family()));
  edit(j);
  return j.dump();
}

}  // namespace

TEST(IoFamilyFile, WhatIsWrittenReadsBack) {
  TempDir dir;
  const FamilyFile f = sample_family();
  write_family_json(dir / "family.json", f);
  const FamilyFile r = read_family_json(dir / "family.json");
  EXPECT_EQ(r.Ts, f.Ts);
  EXPECT_EQ(r.inputs, f.inputs);
  EXPECT_EQ(r.outputs, f.outputs);
  EXPECT_EQ(r.condition_names, f.condition_names);
  ASSERT_EQ(r.members.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string who = "member " + std::to_string(k);
    EXPECT_EQ(r.members[k].log, f.members[k].log) << who;
    EXPECT_EQ(r.members[k].validate, f.members[k].validate) << who;
    expect_same_model(r.members[k].model, f.members[k].model, who);
    EXPECT_EQ(r.members[k].model.provenance, f.members[k].model.provenance) << who;
    expect_same_values(r.members[k].fit_percent, f.members[k].fit_percent, who + " fit");
    ASSERT_EQ(r.members[k].conditions.size(), 2u);
    EXPECT_EQ(std::get<double>(r.members[k].conditions[0]), std::get<double>(f.members[k].conditions[0])) << who;
    EXPECT_EQ(std::get<std::string>(r.members[k].conditions[1]), std::get<std::string>(f.members[k].conditions[1])) << who;
  }
  EXPECT_TRUE(std::isnan(r.members[2].fit_percent(1))) << "NaN written as null reads back as NaN";
  ASSERT_EQ(r.modes.size(), 2u);
  for (std::size_t j = 0; j < 2; ++j) {
    expect_same_values(r.modes[j].freq_hz, f.modes[j].freq_hz, "mode freq");
    expect_same_values(r.modes[j].damping, f.modes[j].damping, "mode damping");
  }
  ASSERT_TRUE(r.nominal_member.has_value());
  EXPECT_EQ(*r.nominal_member, 1);
  EXPECT_EQ(r.nominal_criterion, f.nominal_criterion);
  expect_same_model(r.nominal_model, f.nominal_model, "nominal");
  ASSERT_TRUE(r.uncertainty.has_value());
  EXPECT_EQ(r.uncertainty->form, "multiplicative-output");
  EXPECT_EQ(r.uncertainty->band_lo_hz, 0.5);
  EXPECT_EQ(r.uncertainty->band_hi_hz, 100.0);
  EXPECT_EQ(r.uncertainty->frequency_hz, f.uncertainty->frequency_hz);
  EXPECT_EQ(r.uncertainty->bound, f.uncertainty->bound) << "bit-exact, 1/30 included";
  EXPECT_EQ(r.uncertainty->allowance, f.uncertainty->allowance);
  ASSERT_TRUE(r.uncertainty->weight.has_value());
  expect_same_model(*r.uncertainty->weight, *f.uncertainty->weight, "weight");
  EXPECT_EQ(r.uncertainty->weight_fit, f.uncertainty->weight_fit);
}

TEST(IoFamilyFile, TheJsonHasTheContractsKeysAndTypes) {
  const FamilyFile f = sample_family();
  const nlohmann::json j = nlohmann::json::parse(family_to_json_string(f));
  EXPECT_EQ(j["type"], "family");
  EXPECT_EQ(j["conditions"], nlohmann::json({"payload_kg", "side"}));
  EXPECT_TRUE(j["members"][1]["conditions"]["payload_kg"].is_number());
  EXPECT_EQ(j["members"][1]["conditions"]["payload_kg"].get<double>(), 0.5);
  EXPECT_TRUE(j["members"][1]["conditions"]["side"].is_string());
  EXPECT_TRUE(j["members"][2]["fit_percent"][1].is_null());
  EXPECT_TRUE(j["modes"][1]["freq_hz"][1].is_null());
  EXPECT_TRUE(j["modes"][1]["damping"][1].is_null());
  EXPECT_EQ(j["members"][1]["validate"], "runs/v1.csv");
  EXPECT_FALSE(j["members"][0].contains("validate")) << "no validate log: no key";
  EXPECT_EQ(j["nominal"]["member"], 1);
  EXPECT_EQ(j["uncertainty"]["band_hz"], nlohmann::json({0.5, 100.0}));
  // The keys in the contract's order.
  const nlohmann::ordered_json o = nlohmann::ordered_json::parse(family_to_json_string(f));
  std::vector<std::string> keys;
  for (auto it = o.begin(); it != o.end(); ++it) keys.push_back(it.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"type", "Ts", "inputs", "outputs", "conditions", "members", "modes", "nominal",
                                            "uncertainty"}));
}

TEST(IoFamilyFile, EveryModelObjectInsideIsAModelFile) {
  const FamilyFile f = sample_family();
  const nlohmann::json j = nlohmann::json::parse(family_to_json_string(f));
  for (std::size_t k = 0; k < 3; ++k)
    expect_same_model(model_from_json_value(j["members"][k]["model"], "member"), f.members[k].model, "member");
  expect_same_model(model_from_json_value(j["nominal"]["model"], "nominal"), f.nominal_model, "nominal");
  expect_same_model(model_from_json_value(j["uncertainty"]["weight"], "weight"), *f.uncertainty->weight, "weight");
  // ... and as the text of a model file.
  expect_same_model(model_from_json_string(j["members"][1]["model"].dump(), "m.json"), f.members[1].model, "text");
  EXPECT_FALSE(is_family_json(j["members"][0]["model"]));
  EXPECT_TRUE(is_family_json(j));
}

TEST(IoFamilyFile, NullNominalMemberAndAbsentUncertaintyAndWeight) {
  FamilyFile f = sample_family();
  f.nominal_member.reset();
  f.uncertainty->weight.reset();
  FamilyFile r = family_from_json_string(family_to_json_string(f), "f.json");
  EXPECT_FALSE(r.nominal_member.has_value());
  ASSERT_TRUE(r.uncertainty.has_value());
  EXPECT_FALSE(r.uncertainty->weight.has_value());
  const nlohmann::json j = nlohmann::json::parse(family_to_json_string(f));
  EXPECT_TRUE(j["nominal"]["member"].is_null());
  EXPECT_TRUE(j["uncertainty"]["weight"].is_null());

  f.uncertainty.reset();
  r = family_from_json_string(family_to_json_string(f), "f.json");
  EXPECT_FALSE(r.uncertainty.has_value());
  EXPECT_TRUE(nlohmann::json::parse(family_to_json_string(f))["uncertainty"].is_null());
  // The nominal model is still there.
  expect_same_model(r.nominal_model, f.nominal_model, "nominal");
}

TEST(IoFamilyFile, InconsistentFamiliesAreNotWritten) {
  FamilyFile f = sample_family();
  f.members[1].conditions.pop_back();
  EXPECT_THROW(family_to_json_string(f), std::invalid_argument);
  f = sample_family();
  f.modes[0].freq_hz = vec({1.0, 2.0});
  EXPECT_THROW(family_to_json_string(f), std::invalid_argument);
  f = sample_family();
  f.uncertainty->bound = vec({1.0});
  EXPECT_THROW(family_to_json_string(f), std::invalid_argument);
}

TEST(IoFamilyFile, BadFilesNameTheKey) {
  using nlohmann::json;
  auto has = [](const std::string& text, const std::string& part) {
    EXPECT_NE(text.find(part), std::string::npos) << text;
  };
  // A member's model with a mis-sized A: the member and the model's own key.
  const std::string a = error_text(edited([](json& j) { j["members"][1]["model"]["A"] = json::array({json::array({1.0})}); }));
  has(a, "fam.json: members[1].model: ");  // then the model reader's own message
  has(a, "expected a list of 1 row");
  has(error_text(edited([](json& j) { j["members"][2].erase("model"); })), "members[2]: missing required key 'model'");
  has(error_text(edited([](json& j) { j["members"][0]["conditions"]["side"] = true; })), "members[0].conditions.side");
  has(error_text(edited([](json& j) { j["members"][0]["conditions"].erase("side"); })), "members[0].conditions");
  has(error_text(edited([](json& j) { j["members"][0]["fit_percent"][0] = "high"; })), "members[0].fit_percent[0]");
  has(error_text(edited([](json& j) { j["modes"][1]["freq_hz"].erase(0); })), "modes[1]");
  has(error_text(edited([](json& j) { j["nominal"]["member"] = 3; })), "nominal.member");
  has(error_text(edited([](json& j) { j["nominal"]["member"] = 0.5; })), "nominal.member");
  has(error_text(edited([](json& j) { j["nominal"]["model"]["D"] = "x"; })), "nominal.model");
  has(error_text(edited([](json& j) { j.erase("nominal"); })), "'nominal'");
  has(error_text(edited([](json& j) { j["uncertainty"]["bound"].erase(0); })), "uncertainty.bound");
  has(error_text(edited([](json& j) { j["uncertainty"]["band_hz"] = json::array({1.0}); })), "uncertainty.band_hz");
  has(error_text(edited([](json& j) { j["uncertainty"]["weight"]["B"] = json::array(); })), "uncertainty.weight");
  has(error_text(edited([](json& j) { j["members"] = json::array(); })), "members");
  has(error_text(edited([](json& j) { j["Ts"] = "fast"; })), "Ts");
  has(error_text(edited([](json& j) { j["type"] = "state-space"; })), "family file");
  // Not JSON: the line of the syntax error.
  const std::string syntax = error_text("{\n  \"type\": \"family\",\n  \"Ts\": ]\n}\n");
  has(syntax, "fam.json:3:");
  TempDir dir;
  EXPECT_THROW(read_family_json(dir / "missing.json"), DataError);
}

}  // namespace test_unit_io_family_file
