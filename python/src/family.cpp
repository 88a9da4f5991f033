// sysid.family and sysid.read_family: a model family's modes, nominal,
// uncertainty bound and weight from models identified in Python
// (family/model_family.hpp), as the family file `sysid family` writes
// (io/family_file.hpp: one piece of code for both).
#include <sysid/family/model_family.hpp>
#include <sysid/io/family_file.hpp>

#include <nanobind/stl/pair.h>

#include "bindings.hpp"

namespace sysid::python {

namespace {

/// The family file as a dict (the JSON's structure), with Model objects where the
/// file holds models (members[i]["model"], nominal["model"], uncertainty["weight"]).
nb::object family_to_python(const FamilyFile& f) {
  nb::object out = to_python(nlohmann::json::parse(family_to_json_string(f)));
  nb::list members = nb::cast<nb::list>(out["members"]);
  for (std::size_t k = 0; k < f.members.size(); ++k) members[k]["model"] = nb::cast(f.members[k].model);
  out["nominal"]["model"] = nb::cast(f.nominal_model);
  if (f.uncertainty && f.uncertainty->weight) out["uncertainty"]["weight"] = nb::cast(*f.uncertainty->weight);
  return out;
}

std::vector<Condition> conditions_from_python(const std::optional<nb::dict>& conditions, std::size_t members) {
  std::vector<Condition> out;
  if (!conditions) return out;
  for (const auto& [key, values] : *conditions) {
    Condition c;
    c.name = nb::cast<std::string>(nb::str(key));
    for (const nb::handle v : values) {
      if (nb::isinstance<nb::str>(v))
        c.values.emplace_back(nb::cast<std::string>(v));
      else if (nb::isinstance<nb::float_>(v) || nb::isinstance<nb::int_>(v))
        c.values.emplace_back(nb::cast<double>(v));
      else
        throw std::invalid_argument("conditions['" + c.name + "']: expected numbers or strings");
    }
    if (c.values.size() != members)
      throw std::invalid_argument("conditions['" + c.name + "']: expected one value per model (" + std::to_string(members) +
                                  "), found " + std::to_string(c.values.size()));
    out.push_back(std::move(c));
  }
  return out;
}

nb::object family(const std::vector<ModelFile>& models, const std::optional<std::vector<std::pair<std::optional<SampleArray>, SampleArray>>>& data,
                  const std::optional<nb::dict>& conditions, const std::optional<std::vector<std::string>>& logs,
                  std::optional<std::pair<double, double>> band, const std::string& uncertainty, int weight_order,
                  std::optional<int> nominal, const std::optional<Path>& out) {
  if (models.empty()) throw std::invalid_argument("family: need at least one model");
  if (data && data->size() != models.size())
    throw std::invalid_argument("data: expected one (u, y) pair per model (" + std::to_string(models.size()) + ")");
  if (logs && logs->size() != models.size()) throw std::invalid_argument("logs: expected one name per model");
  ModelFamilyOptions options;
  options.band_hz = band;
  options.bound.form = uncertainty_form_from_name(uncertainty);
  options.weight_order = weight_order;
  options.bound.nominal_member = nominal;
  const std::vector<Condition> condition_list = conditions_from_python(conditions, models.size());
  std::vector<IoData> records;
  if (data)
    for (std::size_t k = 0; k < models.size(); ++k)
      records.push_back(io_data((*data)[k].first, (*data)[k].second, models[k].model.Ts, {}, {}));
  FamilyFile file;
  std::vector<std::string> warnings;
  {
    nb::gil_scoped_release release;
    std::vector<FamilyMemberModel> members;
    std::vector<FamilyFileMember> file_members;
    for (std::size_t k = 0; k < models.size(); ++k) {
      // As `sysid family` (io/family_file.hpp family_member_evidence).
      FamilyMemberEvidence evidence = family_member_evidence(models[k], data ? &records[k] : nullptr, nullptr);
      FamilyFileMember fm;
      fm.log = logs ? (*logs)[k] : std::string();
      fm.model = models[k];
      fm.fit_percent = std::move(evidence.fit_percent);
      members.push_back(std::move(evidence.member));
      file_members.push_back(std::move(fm));
    }
    const ModelFamilyResult result = analyse_model_family(members, options);
    warnings = result.warnings;
    file = make_family_file(std::move(file_members), condition_list, result, options);
    if (out) write_family_json(out->string(), file);
  }
  issue_warnings(warnings);
  return family_to_python(file);
}

nb::object read_family(const Path& path) { return family_to_python(read_family_json(path.string())); }

}  // namespace

void bind_family(nb::module_& m) {
  m.def("family", &family, nb::arg("models"), nb::kw_only(), nb::arg("data") = nb::none(), nb::arg("conditions") = nb::none(),
        nb::arg("logs") = nb::none(), nb::arg("band") = nb::none(), nb::arg("uncertainty") = "multiplicative-output",
        nb::arg("weight_order") = 4, nb::arg("nominal") = nb::none(), nb::arg("out") = nb::none(),
        "A model family over operating conditions, as `sysid family` derives it: the modes followed across the\n"
        "models with their spread against each condition, the nominal (default: the member whose bound has the\n"
        "smallest peak), the uncertainty bound over the band (uncertainty: 'multiplicative-output',\n"
        "'multiplicative-input' or 'additive') and a stable, minimum-phase weight of weight_order poles that\n"
        "covers it at every listed frequency.\n"
        "models: one Model per condition (identify them with sysid.n4sid, sysid.arx ... in any way).\n"
        "data: optional (u, y) per model (u None for a time series), the record it was identified on: gives each member's fit, the band\n"
        "the records excite and the allowance for the members' own estimation error in the bound.\n"
        "conditions: {name: [value per model]} (numbers or labels); logs: names written as members' 'log'.\n"
        "band: (lo, hi) Hz (default: the band every record excites, else up to Nyquist).\n"
        "Returns the family file's structure as a dict with Model objects in place of models; out= writes\n"
        "the file (the program's format: `sysid export` turns it into MATLAB variables).");
  m.def("read_family", &read_family, nb::arg("path"),
        "Read a family file (`sysid family --out`) as the dict sysid.family returns.");
}

}  // namespace sysid::python
