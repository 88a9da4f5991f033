// Augmented models and diagnose reports as JSON; layout in
// include/sysid/io/augmented_model_file.hpp.
#include "sysid/io/augmented_model_file.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "sysid/core/errors.hpp"
#include "sysid/diagnose/physics_kind.hpp"

namespace sysid {

namespace {

const char* stage_name(BlockStage s) {
  switch (s) {
    case BlockStage::actuator: return "actuator";
    case BlockStage::plant_feedback: return "plant_feedback";
    case BlockStage::plant_parallel: return "plant_parallel";
    case BlockStage::sensor: return "sensor";
    case BlockStage::coupling: return "coupling";
  }
  return "?";
}

std::vector<std::string> names_or_default(const std::vector<std::string>& names, Eigen::Index count, const char* prefix) {
  std::vector<std::string> out;
  for (Eigen::Index k = 0; k < count; ++k)
    out.push_back(k < static_cast<Eigen::Index>(names.size()) ? names[k] : prefix + std::to_string(k + 1));
  return out;
}

long channel_index(const nlohmann::json& j, const std::vector<std::string>& names, const std::string& where,
                   const std::string& source) {
  if (!j.is_string()) throw DataError(source, 0, 0, where + ": expected a channel name (string)");
  const auto& name = j.get_ref<const std::string&>();
  const auto first = std::find(names.begin(), names.end(), name);
  if (first != names.end()) {
    // The model file format allows repeated channel names; a block naming one of
    // them would otherwise silently act on the first.
    if (const auto second = std::find(first + 1, names.end(), name); second != names.end())
      throw DataError(source, 0, 0,
                      where + ": channel name '" + name + "' is ambiguous (channels " +
                          std::to_string(first - names.begin() + 1) + " and " +
                          std::to_string(second - names.begin() + 1) + " of the nominal have it)");
    return static_cast<long>(first - names.begin());
  }
  std::string known;
  for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
  throw DataError(source, 0, 0, where + ": no channel named '" + name + "' (the nominal has " + known + ")");
}

/// Every parameter the simulation reads, or the DESIGN.md report parameters.
nlohmann::json params_json(const PhysicsBlock& b, bool reported_only) {
  nlohmann::json p = nlohmann::json::object();
  if (reported_only) {
    for (const auto& [name, value] : physics_kind(b.kind).reported(b)) p[name] = value;
    return p;
  }
  for (const char* name : b.info().parameters) p[name] = b.param(name);
  return p;
}

/// The optional "output_quantities" list (DESIGN.md "Model files"): one known
/// name per output; empty when absent.
std::vector<OutputQuantity> output_quantities_from_file(const ModelFile& file, const std::string& source) {
  std::vector<OutputQuantity> out;
  if (!file.extra.contains("output_quantities")) return out;
  const auto& list = file.extra["output_quantities"];
  const Eigen::Index l = file.model.outputs();
  if (!list.is_array() || static_cast<Eigen::Index>(list.size()) != l)
    throw DataError(source, 0, 0, "output_quantities: expected a list of " + std::to_string(l) +
                                      " names (one per output: position, velocity, acceleration or other)");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string where = "output_quantities[" + std::to_string(i) + "]";
    if (!list[i].is_string()) throw DataError(source, 0, 0, where + ": expected a name (position, velocity, acceleration or other)");
    try {
      out.push_back(parse_output_quantity(list[i].get<std::string>()));
    } catch (const std::invalid_argument& e) {
      throw DataError(source, 0, 0, where + ": " + e.what());
    }
  }
  return out;
}

/// name -> value, a non-finite value (a parameter the data cannot identify) as null.
nlohmann::json finite_or_null(const std::map<std::string, double>& values) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [name, value] : values) j[name] = std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
  return j;
}

nlohmann::json range_json(const std::optional<std::pair<double, double>>& r) {
  if (!r) return nullptr;
  return nlohmann::json::array({r->first, r->second});
}

}  // namespace

AugmentedModel augmented_model_from_file(const ModelFile& file, const std::string& source) {
  AugmentedModel m;
  m.nominal = file.model;
  m.x0 = file.x0;
  m.input_offset = file.input_offset;
  m.output_offset = file.output_offset;
  m.output_quantities = output_quantities_from_file(file, source);
  if (file.type != "augmented") return m;
  const auto inputs = names_or_default(file.model.input_names, file.model.inputs(), "u");
  const auto outputs = names_or_default(file.model.output_names, file.model.outputs(), "y");
  if (file.extra.contains("substeps")) {
    const auto& s = file.extra["substeps"];
    if (!s.is_number_integer() || s.get<long>() < 1 || s.get<long>() > 1000)
      throw DataError(source, 0, 0, "substeps: expected an integer in 1..1000");
    m.substeps = s.get<int>();
  }
  if (!file.extra.contains("blocks")) return m;
  const auto& blocks = file.extra["blocks"];
  if (!blocks.is_array()) throw DataError(source, 0, 0, "blocks: expected a list of blocks");
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    const std::string where = "blocks[" + std::to_string(k) + "]";
    const auto& j = blocks[k];
    if (!j.is_object() || !j.contains("kind") || !j["kind"].is_string())
      throw DataError(source, 0, 0, where + ": expected an object with a \"kind\"");
    PhysicsBlock b;
    b.kind = j["kind"].get<std::string>();
    try {
      (void)b.info();
    } catch (const std::invalid_argument& e) {
      throw DataError(source, 0, 0, where + ".kind: " + e.what());
    }
    b.input = j.contains("input") ? channel_index(j["input"], inputs, where + ".input", source) : 0;
    b.output = j.contains("output") ? channel_index(j["output"], outputs, where + ".output", source) : 0;
    if (!j.contains("params") || !j["params"].is_object()) throw DataError(source, 0, 0, where + ".params: expected an object");
    for (const char* name : b.info().parameters) {
      const auto& p = j["params"];
      double fallback = 0.0;
      if (!p.contains(name) && optional_parameter_default(b, name, fallback)) {
        b.params[name] = fallback;
        continue;
      }
      if (!p.contains(name)) throw DataError(source, 0, 0, where + ".params: missing '" + std::string(name) + "'");
      if (!p[name].is_number() || !std::isfinite(p[name].get<double>()))
        throw DataError(source, 0, 0, where + ".params." + name + ": expected a finite number");
      b.params[name] = p[name].get<double>();
    }
    try {
      check_physics_blocks({b}, m.nominal.inputs(), m.nominal.outputs(), m.nominal.Ts);
    } catch (const std::invalid_argument& e) {
      throw DataError(source, 0, 0, where + ": " + e.what());
    }
    m.blocks.push_back(b);
  }
  return m;
}

ModelFile augmented_model_to_file(const AugmentedModel& model, const nlohmann::json& provenance) {
  ModelFile f;
  f.type = model.blocks.empty() ? "state-space" : "augmented";
  f.model = model.nominal;
  f.x0 = model.x0;
  f.input_offset = model.input_offset;
  f.output_offset = model.output_offset;
  f.provenance = provenance;
  if (std::any_of(model.output_quantities.begin(), model.output_quantities.end(),
                  [](OutputQuantity q) { return q != OutputQuantity::unknown; })) {
    nlohmann::json list = nlohmann::json::array();
    // An output whose quantity is still unknown is written as "other": the file
    // format has no "unknown" (absent means every output unknown).
    for (OutputQuantity q : model.output_quantities) list.push_back(q == OutputQuantity::unknown ? "other" : quantity_name(q));
    f.extra["output_quantities"] = list;
  }
  if (model.blocks.empty()) return f;
  const auto inputs = names_or_default(model.nominal.input_names, model.nominal.inputs(), "u");
  const auto outputs = names_or_default(model.nominal.output_names, model.nominal.outputs(), "y");
  nlohmann::json blocks = nlohmann::json::array();
  for (const auto& b : model.blocks)
    blocks.push_back({{"kind", b.kind},
                      {"input", inputs.at(b.input)},
                      {"output", outputs.at(b.output)},
                      {"connection", stage_name(b.info().stage)},
                      {"params", params_json(b, false)}});
  f.extra["blocks"] = blocks;
  f.extra["substeps"] = model.substeps;
  return f;
}

nlohmann::json diagnose_report_to_json(const DiagnoseReport& r, double Ts) {
  const StateSpace& nom = r.augmented.nominal;
  const auto inputs = names_or_default(nom.input_names, nom.inputs(), "u");
  const auto outputs = names_or_default(nom.output_names, nom.outputs(), "y");
  auto per_output = [&](const Eigen::VectorXd& v) {
    nlohmann::json j = nlohmann::json::object();
    for (Eigen::Index i = 0; i < v.size(); ++i) j[outputs[i]] = v[i];
    return j;
  };
  nlohmann::json findings = nlohmann::json::array();
  for (const auto& f : r.findings) {
    const PhysicsBlock& b = f.candidate.block;
    nlohmann::json windows = nullptr;
    if (!f.time_windows_s.empty()) {
      windows = nlohmann::json::array();
      for (const auto& [t0, t1] : f.time_windows_s) windows.push_back({t0, t1});
    }
    // DESIGN.md reports cross_coupling by the channels it couples.
    const nlohmann::json reported = b.kind == "cross_coupling"
                                        ? nlohmann::json{{"input", inputs.at(b.input)}, {"output", outputs.at(b.output)}}
                                        : params_json(b, true);
    findings.push_back({{"kind", b.kind},
                        {"params", reported},
                        {"fit_before", f.fit_before},
                        {"fit_after", f.fit_after},
                        {"location",
                         {{"freq_hz", range_json(f.band_hz)},
                          {"time_s", windows},
                          {"input", inputs.at(b.input)},
                          {"output", outputs.at(b.output)}}},
                        {"evidence",
                         {{"detector", f.candidate.evidence},
                          {"alternative", f.alternative},
                          {"where", f.where.empty() ? nlohmann::json(nullptr) : nlohmann::json(f.where)},
                          {"detector_score", f.candidate.detector_score},
                          {"selection_gain_points", f.selection_gain},
                          {"t_statistic", f.t_statistic}}},
                        {"model_params", params_json(b, false)},
                        {"uncertainty", finite_or_null(f.uncertainty)},
                        {"parameter_evidence", f.parameter_evidence},
                        {"summary", f.summary}});
  }
  nlohmann::json considered = nlohmann::json::array();
  const auto reading_json = [&](const std::vector<OutputQuantity>& q) {
    nlohmann::json j = nlohmann::json::object();
    for (std::size_t i = 0; i < q.size() && i < outputs.size(); ++i) j[outputs[i]] = quantity_name(q[i]);
    return j;
  };
  for (const auto& c : r.considered)
    considered.push_back({{"kind", c.candidate.block.kind},
                          {"reading", c.candidate.output_quantities.empty() ? nlohmann::json(nullptr)
                                                                             : reading_json(c.candidate.output_quantities)},
                          {"input", inputs.at(c.candidate.block.input)},
                          {"output", outputs.at(c.candidate.block.output)},
                          {"round", c.round},
                          {"detector_score", c.candidate.detector_score},
                          {"selection_gain_points", c.selection_gain},
                          {"t_statistic", c.t_statistic},
                          {"t_threshold", c.t_threshold},
                          {"significant", c.significant},
                          {"standard_errors", finite_or_null(c.standard_errors)},
                          {"parameters_significant", c.parameters_significant},
                          {"parameter_evidence", c.parameter_evidence},
                          {"params", params_json(c.candidate.block, false)}});
  nlohmann::json j = {{"fit_before", r.fit_before},
                      {"fit_after", r.fit_after},
                      {"validation", r.validation},
                      {"findings", findings},
                      {"fit_before_per_output", per_output(r.fit_before_per_output)},
                      {"fit_after_per_output", per_output(r.fit_after_per_output)},
                      {"output_quantities", reading_json(r.output_quantities)},
                      {"output_quantity_note", r.reading_note.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.reading_note)},
                      {"closed_loop",
                       {{"tested", r.closed_loop.tested},
                        {"detected", r.closed_loop.feedback_detected},
                        {"statistic", r.closed_loop.statistic},
                        {"threshold", r.closed_loop.threshold},
                        {"evidence", r.closed_loop.evidence}}},
                      {"mismatch_detected", r.location.any_mismatch},
                      {"mismatch_tests_fired", r.location.fired},
                      {"candidates", considered},
                      {"Ts", Ts},
                      {"warnings", r.warnings}};
  if (r.nominal_refit.attempted) {
    auto pole_list = [](const Eigen::VectorXcd& p) {
      nlohmann::json list = nlohmann::json::array();
      for (Eigen::Index k = 0; k < p.size(); ++k) list.push_back({p[k].real(), p[k].imag()});
      return list;
    };
    j["nominal_refit"] = {{"applied", r.nominal_refit.applied},
                          {"poles_before", pole_list(r.nominal_refit.poles_before)},
                          {"poles_after", pole_list(r.nominal_refit.poles_after)}};
  }
  return j;
}

}  // namespace sysid
