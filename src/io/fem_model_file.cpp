#include "sysid/io/fem_model_file.hpp"
#include "sysid/io/model_json.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <utility>
#include <vector>

#include "sysid/core/errors.hpp"
#include "sysid/io/atomic_file.hpp"
#include "io/detail/json_messages.hpp"
#include "sysid/io/matrix_market.hpp"

namespace sysid {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

const char* const k_top_keys[] = {"type", "mass", "stiffness", "damping", "inputs", "outputs", "length_unit",
                                  "description"};

std::string join(const std::string& where, const std::string& key) { return where.empty() ? key : where + "." + key; }

template <std::size_t N>
void refuse_unknown_keys(const json& obj, const std::string& where, const char* const (&allowed)[N]) {
  for (const auto& item : obj.items()) {
    if (std::find_if(std::begin(allowed), std::end(allowed), [&](const char* k) { return item.key() == k; }) !=
        std::end(allowed))
      continue;
    std::string list;
    for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
    detail::throw_data_error_at(join(where, item.key()), "unknown key (accepted here: " + list + ")");
  }
}

const json& required(const json& obj, const std::string& where, const char* key) {
  if (!obj.contains(key)) {
    if (where.empty()) throw DataError(std::string("missing required key '") + key + "'");
    detail::throw_data_error_at(where, std::string("missing required key '") + key + "'");
  }
  return obj[key];
}

std::string string_value(const json& j, const std::string& key, bool allow_empty) {
  if (!j.is_string() || (!allow_empty && j.get<std::string>().empty()))
    detail::throw_data_error_at(key, std::string("expected a ") + (allow_empty ? "" : "non-empty ") + "string, found " + detail::describe_json_value(j));
  return j.get<std::string>();
}

double non_negative_number(const json& j, const std::string& key) {
  if (!j.is_number()) detail::throw_data_error_at(key, "expected a number >= 0, found " + detail::describe_json_value(j));
  const double v = j.get<double>();
  if (!std::isfinite(v) || v < 0.0) detail::throw_data_error_at(key, "expected a number >= 0, found " + detail::describe_json_value(j));
  return v;
}

Eigen::Index dof_value(const json& j, const std::string& key) {
  const std::string expected = "expected a non-negative integer (0-based row of the matrices), found ";
  if (j.is_number_unsigned()) {
    const auto v = j.get<std::uint64_t>();
    if (v > static_cast<std::uint64_t>(std::numeric_limits<Eigen::Index>::max())) detail::throw_data_error_at(key, expected + detail::describe_json_value(j));
    return static_cast<Eigen::Index>(v);
  }
  if (!j.is_number_integer() || j.get<std::int64_t>() < 0) detail::throw_data_error_at(key, expected + detail::describe_json_value(j));
  return static_cast<Eigen::Index>(j.get<std::int64_t>());
}

const json& object_value(const json& j, const std::string& key) {
  if (!j.is_object()) detail::throw_data_error_at(key, "expected an object {...}, found " + detail::describe_json_value(j));
  return j;
}

const json& list_value(const json& j, const std::string& key) {
  if (!j.is_array() || j.empty()) detail::throw_data_error_at(key, "expected a non-empty list [...], found " + detail::describe_json_value(j));
  return j;
}

std::string default_output_unit(fem::Quantity quantity, const std::string& length_unit) {
  switch (quantity) {
    case fem::Quantity::displacement: return length_unit;
    case fem::Quantity::velocity: return length_unit + "/s";
    case fem::Quantity::acceleration: return length_unit + "/s^2";
  }
  return length_unit;
}

/// Matrix file names as written in the JSON, read after the whole JSON checked out
/// (a typo is reported before megabytes of matrices are parsed).
struct MatrixNames {
  std::string mass, stiffness, damping;
};

void read_damping(const json& root, fem::SecondOrderModel& model, MatrixNames& names) {
  if (!root.contains("damping")) return;
  const json& d = object_value(root["damping"], "damping");
  static const char* const kinds[] = {"matrix", "rayleigh", "modal_ratio"};
  std::string found;
  std::size_t count = 0;
  for (const auto& item : d.items()) {
    found += (found.empty() ? "" : ", ") + item.key();
    if (std::find_if(std::begin(kinds), std::end(kinds), [&](const char* k) { return item.key() == k; }) !=
        std::end(kinds))
      ++count;
  }
  if (count != 1 || d.size() != 1)
    detail::throw_data_error_at("damping", "expected exactly one of matrix, rayleigh, modal_ratio, found " +
                        (found.empty() ? std::string("none") : found));
  if (d.contains("matrix")) {
    model.damping.kind = fem::DampingKind::matrix;
    names.damping = string_value(d["matrix"], "damping.matrix", false);
  } else if (d.contains("rayleigh")) {
    const json& r = object_value(d["rayleigh"], "damping.rayleigh");
    static const char* const coefficients[] = {"alpha", "beta"};
    refuse_unknown_keys(r, "damping.rayleigh", coefficients);
    model.damping.kind = fem::DampingKind::rayleigh;
    if (r.contains("alpha")) model.damping.alpha = non_negative_number(r["alpha"], "damping.rayleigh.alpha");
    if (r.contains("beta")) model.damping.beta = non_negative_number(r["beta"], "damping.rayleigh.beta");
  } else {
    model.damping.kind = fem::DampingKind::modal_ratio;
    model.damping.ratio = non_negative_number(d["modal_ratio"], "damping.modal_ratio");
  }
}

void read_signals(const json& root, fem::SecondOrderModel& model, const std::string& length_unit) {
  static const char* const input_keys[] = {"name", "dof", "unit"};
  const json& inputs = list_value(required(root, "", "inputs"), "inputs");
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const std::string where = "inputs[" + std::to_string(i) + "]";
    const json& s = object_value(inputs[i], where);
    refuse_unknown_keys(s, where, input_keys);
    fem::ForceInput input;
    input.name = string_value(required(s, where, "name"), where + ".name", false);
    input.dof = dof_value(required(s, where, "dof"), where + ".dof");
    if (s.contains("unit")) input.unit = string_value(s["unit"], where + ".unit", true);
    model.inputs.push_back(std::move(input));
  }

  static const char* const output_keys[] = {"name", "dof", "quantity", "unit"};
  const json& outputs = list_value(required(root, "", "outputs"), "outputs");
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const std::string where = "outputs[" + std::to_string(i) + "]";
    const json& s = object_value(outputs[i], where);
    refuse_unknown_keys(s, where, output_keys);
    fem::DofOutput output;
    output.name = string_value(required(s, where, "name"), where + ".name", false);
    output.dof = dof_value(required(s, where, "dof"), where + ".dof");
    const json& q = required(s, where, "quantity");
    const std::string quantity_expected = "expected displacement, velocity or acceleration, found " + detail::describe_json_value(q);
    if (!q.is_string()) detail::throw_data_error_at(where + ".quantity", quantity_expected);
    try {
      output.quantity = fem::quantity_from_name(q.get<std::string>());
    } catch (const std::invalid_argument&) {
      detail::throw_data_error_at(where + ".quantity", quantity_expected);
    }
    output.unit = s.contains("unit") ? string_value(s["unit"], where + ".unit", true)
                                     : default_output_unit(output.quantity, length_unit);
    model.outputs.push_back(std::move(output));
  }
}

/// Everything but the matrices themselves.
fem::SecondOrderModel model_from_root(const json& root, MatrixNames& names) {
  if (!root.is_object()) throw DataError("expected a JSON object {...} at the top level, found " + detail::describe_json_value(root));
  refuse_unknown_keys(root, "", k_top_keys);
  const json& type = required(root, "", "type");
  if (!type.is_string() || type.get<std::string>() != "fem") detail::throw_data_error_at("type", "expected \"fem\", found " + detail::describe_json_value(type));

  fem::SecondOrderModel model;
  names.mass = string_value(required(root, "", "mass"), "mass", false);
  names.stiffness = string_value(required(root, "", "stiffness"), "stiffness", false);
  read_damping(root, model, names);
  const std::string length_unit =
      root.contains("length_unit") ? string_value(root["length_unit"], "length_unit", false) : std::string("m");
  if (root.contains("description")) string_value(root["description"], "description", true);
  read_signals(root, model, length_unit);
  return model;
}

std::string resolve(const fs::path& directory, const std::string& name) {
  const fs::path p(name);
  return p.is_absolute() ? p.string() : (directory / p).string();
}

}  // namespace

fem::SecondOrderModel read_fem_model(const std::string& json_path) {
  const std::string text = read_whole_file(json_path);
  const json root = parse_json_text(text, json_path);
  MatrixNames names;
  fem::SecondOrderModel model;
  try {
    model = model_from_root(root, names);
  } catch (const DataError& e) {
    if (!e.file().empty()) throw;
    throw DataError(json_path, 0, 0, e.message());
  }

  // Matrix Market errors carry their own file, line and column: let them through.
  const fs::path directory = fs::path(json_path).parent_path();
  model.mass = read_matrix_market(resolve(directory, names.mass));
  model.stiffness = read_matrix_market(resolve(directory, names.stiffness));
  if (model.damping.kind == fem::DampingKind::matrix)
    model.damping_matrix = read_matrix_market(resolve(directory, names.damping));

  try {
    model.validate();
  } catch (const std::invalid_argument& e) {
    throw DataError(json_path, 0, 0, std::string("invalid model: ") + e.what());
  }
  return model;
}

void write_fem_model(const std::string& json_path, const fem::SecondOrderModel& model, const std::string& description) {
  model.validate();
  const fs::path path(json_path);
  const std::string stem = path.stem().string();
  if (stem.empty() || !path.has_filename())
    throw std::invalid_argument("write_fem_model: json_path must name a file, is '" + json_path + "'");
  const fs::path directory = path.parent_path();

  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  out["type"] = "fem";
  if (!description.empty()) out["description"] = description;

  // Matrices first, the JSON that names them last.
  auto write_matrix = [&](const Eigen::SparseMatrix<double>& matrix, const char* letter) {
    const std::string name = stem + "." + letter + ".mtx";
    write_matrix_market((directory / name).string(), matrix, is_exactly_symmetric(matrix));
    return name;
  };
  out["mass"] = write_matrix(model.mass, "M");
  out["stiffness"] = write_matrix(model.stiffness, "K");
  switch (model.damping.kind) {
    case fem::DampingKind::none: break;
    case fem::DampingKind::matrix: out["damping"] = {{"matrix", write_matrix(model.damping_matrix, "C")}}; break;
    case fem::DampingKind::rayleigh:
      out["damping"]["rayleigh"] = {{"alpha", model.damping.alpha}, {"beta", model.damping.beta}};
      break;
    case fem::DampingKind::modal_ratio: out["damping"] = {{"modal_ratio", model.damping.ratio}}; break;
  }

  out["inputs"] = nlohmann::ordered_json::array();
  for (const fem::ForceInput& input : model.inputs)
    out["inputs"].push_back({{"name", input.name}, {"dof", input.dof}, {"unit", input.unit}});
  out["outputs"] = nlohmann::ordered_json::array();
  for (const fem::DofOutput& output : model.outputs)
    out["outputs"].push_back({{"name", output.name},
                              {"dof", output.dof},
                              {"quantity", fem::quantity_name(output.quantity)},
                              {"unit", output.unit}});
  write_file_atomically(json_path, out.dump(2) + "\n");
}

}  // namespace sysid
