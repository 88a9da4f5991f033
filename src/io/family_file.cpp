// Implementation of io/family_file.hpp (format in DESIGN.md and the header).
#include <sysid/io/family_file.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/validate/compare.hpp>

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace sysid {

namespace {

using nlohmann::json;
using nlohmann::ordered_json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ordered_json list_or_null(const Eigen::VectorXd& v) {
  ordered_json j = ordered_json::array();
  for (Eigen::Index k = 0; k < v.size(); ++k) j.push_back(std::isfinite(v(k)) ? ordered_json(v(k)) : ordered_json(nullptr));
  return j;
}

ordered_json number_or_null(double x) { return std::isfinite(x) ? ordered_json(x) : ordered_json(nullptr); }

ordered_json condition_json(const ConditionValue& v) {
  if (const double* d = std::get_if<double>(&v)) return number_or_null(*d);
  return std::get<std::string>(v);
}

ordered_json spread_json(const ModeSpread& s) {
  ordered_json j;
  j["present"] = s.present;
  j["freq_hz"] = {{"mean", number_or_null(s.freq_mean)}, {"min", number_or_null(s.freq_min)}, {"max", number_or_null(s.freq_max)}};
  j["damping"] = {{"mean", number_or_null(s.damping_mean)}, {"min", number_or_null(s.damping_min)},
                  {"max", number_or_null(s.damping_max)}};
  ordered_json effects = ordered_json::object();
  for (const ConditionEffect& e : s.effects) {
    ordered_json ej;
    if (e.numeric) {
      ej["freq_hz_per_unit"] = number_or_null(e.freq_slope);
      ej["freq_hz_per_unit_se"] = number_or_null(e.freq_slope_se);
      ej["damping_per_unit"] = number_or_null(e.damping_slope);
      ej["damping_per_unit_se"] = number_or_null(e.damping_slope_se);
    } else {
      ordered_json f = ordered_json::object(), z = ordered_json::object();
      for (const auto& [label, value] : e.freq_by_label) f[label] = number_or_null(value);
      for (const auto& [label, value] : e.damping_by_label) z[label] = number_or_null(value);
      ej["freq_hz_by_value"] = std::move(f);
      ej["damping_by_value"] = std::move(z);
    }
    effects[e.condition] = std::move(ej);
  }
  j["effects"] = std::move(effects);
  return j;
}

// ---- reading ----

const json& require(const json& obj, const std::string& key, const std::string& where) {
  if (!obj.is_object() || !obj.contains(key)) throw DataError(where + ": missing required key '" + key + "'");
  return obj[key];
}


double number_at(const json& j, const std::string& where) {
  if (!j.is_number()) throw DataError(where + ": expected a number, found " + j.dump());
  return j.get<double>();
}

Eigen::VectorXd numbers_or_null(const json& j, const std::string& where) {
  if (!j.is_array()) throw DataError(where + ": expected a list of numbers, found " + j.dump().substr(0, 60));
  Eigen::VectorXd v(static_cast<Eigen::Index>(j.size()));
  for (std::size_t k = 0; k < j.size(); ++k) {
    if (j[k].is_null())
      v(static_cast<Eigen::Index>(k)) = kNaN;
    else
      v(static_cast<Eigen::Index>(k)) = number_at(j[k], where + "[" + std::to_string(k) + "]");
  }
  return v;
}

std::vector<std::string> strings_at(const json& j, const std::string& where) {
  if (!j.is_array()) throw DataError(where + ": expected a list of names");
  std::vector<std::string> out;
  for (const json& e : j) {
    if (!e.is_string()) throw DataError(where + ": expected names (strings), found " + e.dump());
    out.push_back(e.get<std::string>());
  }
  return out;
}

ModelFile model_at(const json& j, const std::string& where) {
  try {
    return model_from_json_value(j, where);
  } catch (const DataError& e) {
    throw DataError(where + ": " + e.message());
  }
}

FamilyFile family_from_root(const json& root) {
  if (!is_family_json(root)) throw DataError("expected a family file (an object with \"type\": \"family\")");
  FamilyFile f;
  f.Ts = number_at(require(root, "Ts", ""), "Ts");
  f.inputs = strings_at(require(root, "inputs", ""), "inputs");
  f.outputs = strings_at(require(root, "outputs", ""), "outputs");
  f.condition_names = root.contains("conditions") ? strings_at(root["conditions"], "conditions") : std::vector<std::string>{};
  const json& members = require(root, "members", "");
  if (!members.is_array() || members.empty()) throw DataError("members: expected a non-empty list of members");
  for (std::size_t i = 0; i < members.size(); ++i) {
    const std::string where = "members[" + std::to_string(i) + "]";
    const json& m = members[i];
    FamilyFileMember member;
    member.model = model_at(require(m, "model", where), where + ".model");
    if (m.contains("log") && m["log"].is_string()) member.log = m["log"].get<std::string>();
    if (m.contains("validate") && m["validate"].is_string()) member.validate = m["validate"].get<std::string>();
    if (m.contains("fit_percent")) member.fit_percent = numbers_or_null(m["fit_percent"], where + ".fit_percent");
    const json& conditions = m.contains("conditions") ? m["conditions"] : json::object();
    for (const std::string& name : f.condition_names) {
      const json& v = require(conditions, name, where + ".conditions");
      if (v.is_number())
        member.conditions.emplace_back(v.get<double>());
      else if (v.is_string())
        member.conditions.emplace_back(v.get<std::string>());
      else
        throw DataError(where + ".conditions." + name + ": expected a number or a label, found " + v.dump());
    }
    f.members.push_back(std::move(member));
  }
  if (root.contains("modes")) {
    const json& modes = root["modes"];
    if (!modes.is_array()) throw DataError("modes: expected a list");
    for (std::size_t j = 0; j < modes.size(); ++j) {
      const std::string where = "modes[" + std::to_string(j) + "]";
      TrackedMode t;
      t.freq_hz = numbers_or_null(require(modes[j], "freq_hz", where), where + ".freq_hz");
      t.damping = numbers_or_null(require(modes[j], "damping", where), where + ".damping");
      if (t.freq_hz.size() != static_cast<Eigen::Index>(f.members.size()) || t.damping.size() != t.freq_hz.size())
        throw DataError(where + ": expected one frequency and one damping per member (" + std::to_string(f.members.size()) + ")");
      f.modes.push_back(std::move(t));
    }
  }
  if (root.contains("nominal")) {
    const json& n = root["nominal"];
    if (n.contains("member") && !n["member"].is_null()) {
      const double k = number_at(n["member"], "nominal.member");
      if (k < 0 || k >= static_cast<double>(f.members.size()) || k != std::floor(k))
        throw DataError("nominal.member: expected a member index 0.." + std::to_string(f.members.size() - 1));
      f.nominal_member = static_cast<int>(k);
    }
    if (n.contains("criterion") && n["criterion"].is_string()) f.nominal_criterion = n["criterion"].get<std::string>();
    f.nominal_model = model_at(require(n, "model", "nominal"), "nominal.model");
  } else {
    throw DataError("missing required key 'nominal'");
  }
  if (root.contains("uncertainty") && !root["uncertainty"].is_null()) {
    const json& u = root["uncertainty"];
    FamilyFileUncertainty unc;
    if (u.contains("form") && u["form"].is_string()) unc.form = u["form"].get<std::string>();
    const Eigen::VectorXd band = numbers_or_null(require(u, "band_hz", "uncertainty"), "uncertainty.band_hz");
    if (band.size() != 2) throw DataError("uncertainty.band_hz: expected [low, high]");
    unc.band_lo_hz = band(0);
    unc.band_hi_hz = band(1);
    unc.frequency_hz = numbers_or_null(require(u, "frequency_hz", "uncertainty"), "uncertainty.frequency_hz");
    unc.bound = numbers_or_null(require(u, "bound", "uncertainty"), "uncertainty.bound");
    if (unc.bound.size() != unc.frequency_hz.size())
      throw DataError("uncertainty.bound: expected one value per frequency (" + std::to_string(unc.frequency_hz.size()) + ")");
    if (u.contains("allowance") && u["allowance"].is_string()) unc.allowance = u["allowance"].get<std::string>();
    if (u.contains("weight") && !u["weight"].is_null()) unc.weight = model_at(u["weight"], "uncertainty.weight");
    if (u.contains("weight_fit") && u["weight_fit"].is_object()) unc.weight_fit = u["weight_fit"];
    f.uncertainty = std::move(unc);
  }
  return f;
}

}  // namespace

FamilyMemberEvidence family_member_evidence(const ModelFile& file, const IoData* own, const IoData* validation) {
  const StateSpace model = named_model(file);
  FamilyMemberEvidence out{{family_member_model(model, file.K, file.noise_covariance), {}}, {}};
  if (own == nullptr) return out;
  CompareOptions co;
  co.input_offset = file.input_offset;
  co.output_offset = file.output_offset;
  if (model.inputs() == 0) {
    // A simulation without inputs says nothing about a time series.
    co.predict_steps = 1;
    out.fit_percent = compare_fit(model, file.K, validation ? *validation : *own, co);
    return out;
  }
  const Experiment& e = own->experiments.front();
  const CompareResult sim = compare(model, Eigen::MatrixXd(), e, co);
  out.member.error = frequency_response_error(model.order(), e.u, e.y - sim.y_hat, model.Ts);
  out.fit_percent = validation ? compare_fit(model, Eigen::MatrixXd(), *validation, co) : sim.fit_percent;
  return out;
}

FamilyFile make_family_file(std::vector<FamilyFileMember> members, const std::vector<Condition>& conditions,
                            const ModelFamilyResult& result, const ModelFamilyOptions& options) {
  if (members.empty()) throw std::invalid_argument("make_family_file: need at least one member");
  for (const TrackedMode& t : result.modes.modes)
    if (static_cast<std::size_t>(t.freq_hz.size()) != members.size())
      throw std::invalid_argument("make_family_file: the analysis has another number of members");
  FamilyFile f;
  const StateSpace first = named_model(members.front().model);
  f.Ts = first.Ts;
  f.inputs = first.input_names;
  f.outputs = first.output_names;
  for (const Condition& c : conditions) {
    if (c.values.size() != members.size())
      throw std::invalid_argument("make_family_file: condition '" + c.name + "' needs one value per member");
    f.condition_names.push_back(c.name);
  }
  for (std::size_t k = 0; k < members.size(); ++k) {
    members[k].conditions.clear();
    for (const Condition& c : conditions) members[k].conditions.push_back(c.values[k]);
  }
  f.members = std::move(members);
  f.modes = result.modes.modes;
  for (const TrackedMode& t : f.modes) f.mode_spreads.push_back(mode_spread(t, conditions));
  const int nominal = result.bound ? result.bound->nominal_member : 0;
  f.nominal_member = nominal;
  f.nominal_criterion = result.bound ? result.bound->criterion : "the only member";
  f.nominal_model = f.members[static_cast<std::size_t>(nominal)].model;
  if (result.bound) {
    FamilyFileUncertainty u;
    u.form = to_string(options.bound.form);
    u.band_lo_hz = result.band_lo_hz;
    u.band_hi_hz = result.band_hi_hz;
    u.frequency_hz = result.frequency_hz;
    u.bound = result.bound->bound;
    char coverage[32];
    std::snprintf(coverage, sizeof coverage, "%.3g", options.bound.coverage);
    u.allowance = result.bound->with_allowance
                      ? std::string("per member, ") + coverage +
                            " x sqrt(s_member^2 + s_nominal^2) x sigma_max(P0^+) (additive: without the last factor), "
                            "s the standard deviation of the response from (order / samples) x output-error spectrum / "
                            "input spectrum (Ljung 1985)"
                      : "none: some members came without their logs";
    if (result.weight) {
      ModelFile w;
      w.model = result.weight->weight;
      w.provenance = {{"method", "uncertainty weight (family/uncertainty_weight.hpp)"},
                      {"order", result.weight->weight.order()},
                      {"median_conservatism", result.weight->median_conservatism},
                      {"max_conservatism", result.weight->max_conservatism}};
      u.weight = std::move(w);
      u.weight_fit = {{"order", result.weight->weight.order()},
                      {"median_conservatism", result.weight->median_conservatism},
                      {"max_conservatism", result.weight->max_conservatism},
                      {"min_ratio", result.weight->min_ratio}};
    }
    f.uncertainty = std::move(u);
  }
  return f;
}

bool is_family_json(const nlohmann::json& root) {
  return root.is_object() && root.contains("type") && root["type"].is_string() && root["type"].get<std::string>() == "family";
}

std::string family_to_json_string(const FamilyFile& f) {
  const std::size_t n = f.members.size();
  ordered_json top;
  top["type"] = "family";
  top["Ts"] = f.Ts;
  top["inputs"] = f.inputs;
  top["outputs"] = f.outputs;
  top["conditions"] = f.condition_names;
  ordered_json members = ordered_json::array();
  for (std::size_t i = 0; i < n; ++i) {
    const FamilyFileMember& m = f.members[i];
    if (m.conditions.size() != f.condition_names.size())
      throw std::invalid_argument("family_to_json: member " + std::to_string(i) + " needs one value per condition");
    ordered_json mj;
    ordered_json conditions = ordered_json::object();
    for (std::size_t c = 0; c < m.conditions.size(); ++c) conditions[f.condition_names[c]] = condition_json(m.conditions[c]);
    mj["conditions"] = std::move(conditions);
    mj["log"] = m.log;
    if (!m.validate.empty()) mj["validate"] = m.validate;
    mj["model"] = model_to_ordered_json(m.model);
    mj["fit_percent"] = list_or_null(m.fit_percent);
    members.push_back(std::move(mj));
  }
  top["members"] = std::move(members);
  ordered_json modes = ordered_json::array();
  for (std::size_t j = 0; j < f.modes.size(); ++j) {
    const TrackedMode& t = f.modes[j];
    if (static_cast<std::size_t>(t.freq_hz.size()) != n || static_cast<std::size_t>(t.damping.size()) != n)
      throw std::invalid_argument("family_to_json: mode " + std::to_string(j) + " needs one value per member");
    ordered_json mj;
    mj["freq_hz"] = list_or_null(t.freq_hz);
    mj["damping"] = list_or_null(t.damping);
    if (j < f.mode_spreads.size()) mj["spread"] = spread_json(f.mode_spreads[j]);
    modes.push_back(std::move(mj));
  }
  top["modes"] = std::move(modes);
  ordered_json nominal;
  nominal["member"] = f.nominal_member ? ordered_json(*f.nominal_member) : ordered_json(nullptr);
  nominal["criterion"] = f.nominal_criterion;
  nominal["model"] = model_to_ordered_json(f.nominal_model);
  top["nominal"] = std::move(nominal);
  if (f.uncertainty) {
    const FamilyFileUncertainty& u = *f.uncertainty;
    if (u.bound.size() != u.frequency_hz.size()) throw std::invalid_argument("family_to_json: one bound per frequency");
    ordered_json uj;
    uj["form"] = u.form;
    uj["band_hz"] = {u.band_lo_hz, u.band_hi_hz};
    uj["frequency_hz"] = list_or_null(u.frequency_hz);
    uj["bound"] = list_or_null(u.bound);
    uj["allowance"] = u.allowance;
    uj["weight"] = u.weight ? model_to_ordered_json(*u.weight) : ordered_json(nullptr);
    uj["weight_fit"] = ordered_json(u.weight_fit);
    top["uncertainty"] = std::move(uj);
  } else {
    top["uncertainty"] = nullptr;
  }
  return pretty_json(top);
}

FamilyFile family_from_json_string(const std::string& text, const std::string& source_name) {
  return family_from_json_value(parse_json_text(text, source_name), source_name);
}

FamilyFile family_from_json_value(const nlohmann::json& root, const std::string& source_name) {
  try {
    return family_from_root(root);
  } catch (const DataError& e) {
    if (!e.file().empty()) throw;
    throw DataError(source_name, 0, 0, e.message());
  }
}

FamilyFile read_family_json(const std::string& path) { return family_from_json_string(read_whole_file(path), path); }

void write_family_json(const std::string& path, const FamilyFile& family) {
  write_file_atomically(path, family_to_json_string(family));
}

}  // namespace sysid
