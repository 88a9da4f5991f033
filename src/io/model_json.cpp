#include "sysid/io/model_json.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

#include "sysid/core/errors.hpp"
#include "sysid/io/atomic_file.hpp"
#include "io/detail/json_messages.hpp"

namespace sysid {
namespace {

using nlohmann::json;

const char* const k_types[] = {"state-space", "polynomial", "augmented"};

/// Key of the state-space sub-object for a model type; empty for "state-space",
/// whose matrices sit at the top level.
std::string sub_object_key(const std::string& type) {
  if (type == "polynomial") return "state_space";
  if (type == "augmented") return "nominal";
  return {};
}

/// Keys that belong to the state-space part (top level or sub-object).
const std::set<std::string>& state_space_keys() {
  static const std::set<std::string> keys{"Ts", "A", "B", "C", "D", "K", "noise_covariance", "x0", "inputs", "outputs"};
  return keys;
}

/// Keys always at the top level.
const std::set<std::string>& top_level_keys() {
  static const std::set<std::string> keys{"type", "input_offset", "output_offset", "provenance"};
  return keys;
}

std::string shape(Eigen::Index rows, Eigen::Index cols) {
  return std::to_string(rows) + (rows == 1 ? " row of " : " rows of ") + std::to_string(cols) +
         (cols == 1 ? " number" : " numbers");
}

// ---- reading -----------------------------------------------------------------

double number_from_json(const json& j, const std::string& key) {
  if (!j.is_number()) throw DataError(key + ": expected a number, found " + detail::describe_json_value(j));
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw DataError(key + ": NaN or Inf is not allowed in a model file");
  return v;
}

Eigen::VectorXd vector_from_json(const json& j, const std::string& key) {
  if (!j.is_array()) throw DataError(key + ": expected a list of numbers, found " + detail::describe_json_value(j));
  Eigen::VectorXd v(static_cast<Eigen::Index>(j.size()));
  for (std::size_t i = 0; i < j.size(); ++i) {
    const json& e = j[i];
    if (!e.is_number())
      throw DataError(key + ": entry " + std::to_string(i + 1) + " is not a number (found " + detail::describe_json_value(e) + ")");
    v(static_cast<Eigen::Index>(i)) = e.get<double>();
    if (!std::isfinite(v(static_cast<Eigen::Index>(i))))
      throw DataError(key + ": entry " + std::to_string(i + 1) + " is NaN or Inf");
  }
  return v;
}

std::vector<std::string> names_from_json(const json& j, const std::string& key, Eigen::Index expected,
                                         const char* per) {
  if (!j.is_array()) throw DataError(key + ": expected a list of names, found " + detail::describe_json_value(j));
  if (static_cast<Eigen::Index>(j.size()) != expected)
    throw DataError(key + ": expected " + std::to_string(expected) + " names (one per " + per + "), found " +
                    std::to_string(j.size()));
  std::vector<std::string> names;
  for (std::size_t i = 0; i < j.size(); ++i) {
    if (!j[i].is_string())
      throw DataError(key + ": entry " + std::to_string(i + 1) + " is not a string (found " + detail::describe_json_value(j[i]) + ")");
    names.push_back(j[i].get<std::string>());
  }
  return names;
}

void expect_shape(const Eigen::MatrixXd& m, Eigen::Index rows, Eigen::Index cols, const std::string& key,
                  const char* meaning) {
  if (m.rows() != rows || m.cols() != cols)
    throw DataError(key + ": expected a list of " + shape(rows, cols) + " (" + meaning + "), found " +
                    shape(m.rows(), m.cols()));
}

void expect_size(const Eigen::VectorXd& v, Eigen::Index n, const std::string& key, const char* per) {
  if (v.size() != n)
    throw DataError(key + ": expected a list of " + std::to_string(n) + " numbers (one per " + per + "), found " +
                    std::to_string(v.size()));
}

/// Reads the state-space keys of `obj` (top level or sub-object) into `file`.
/// `prefix` ("" or "state_space.") makes messages point at the right place.
void read_state_space_part(const json& obj, const std::string& prefix, ModelFile& file) {
  for (const char* key : {"Ts", "A", "B", "C", "D"})
    if (!obj.contains(key)) throw DataError("missing required key '" + prefix + key + "'");

  StateSpace& ss = file.model;
  ss.Ts = number_from_json(obj["Ts"], prefix + "Ts");
  if (ss.Ts < 0.0)
    throw DataError(prefix + "Ts: expected a sample time >= 0 (seconds; 0 = continuous time), found " +
                    detail::describe_json_value(obj["Ts"]));
  ss.A = matrix_from_json(obj["A"], prefix + "A");
  ss.B = matrix_from_json(obj["B"], prefix + "B");
  ss.C = matrix_from_json(obj["C"], prefix + "C");
  ss.D = matrix_from_json(obj["D"], prefix + "D");

  // n from A; m and l from B and C, or from D when there are no states (then B
  // and C carry no dimension: [] is 0x0 and is given its proper 0 x m / l x 0 shape).
  const Eigen::Index n = ss.A.rows();
  expect_shape(ss.A, n, n, prefix + "A", "square: states x states");
  Eigen::Index m, l;
  if (n == 0) {
    m = ss.D.cols();
    l = ss.D.rows();
    if (ss.B.size() == 0) ss.B.resize(0, m);
    if (ss.C.size() == 0) ss.C.resize(l, 0);
  } else {
    m = ss.B.cols();
    l = ss.C.rows();
  }
  expect_shape(ss.B, n, m, prefix + "B", "states x inputs");
  expect_shape(ss.C, l, n, prefix + "C", "outputs x states");
  expect_shape(ss.D, l, m, prefix + "D", "outputs x inputs");

  if (obj.contains("K")) {
    file.K = matrix_from_json(obj["K"], prefix + "K");
    expect_shape(file.K, n, l, prefix + "K", "states x outputs");
  }
  if (obj.contains("noise_covariance")) {
    file.noise_covariance = matrix_from_json(obj["noise_covariance"], prefix + "noise_covariance");
    expect_shape(file.noise_covariance, l, l, prefix + "noise_covariance", "outputs x outputs");
  }
  if (obj.contains("x0")) {
    file.x0 = vector_from_json(obj["x0"], prefix + "x0");
    expect_size(file.x0, n, prefix + "x0", "state");
  }
  if (obj.contains("inputs")) ss.input_names = names_from_json(obj["inputs"], prefix + "inputs", m, "input");
  if (obj.contains("outputs")) ss.output_names = names_from_json(obj["outputs"], prefix + "outputs", l, "output");

  try {
    ss.validate();
  } catch (const std::invalid_argument& e) {
    throw DataError(std::string("invalid model: ") + e.what());
  }
}

ModelFile model_from_root(const json& root) {
  if (!root.is_object()) throw DataError("expected a JSON object {...} at the top level, found " + detail::describe_json_value(root));
  ModelFile file;
  if (root.contains("type")) {
    const json& t = root["type"];
    if (!t.is_string() || std::find(std::begin(k_types), std::end(k_types), t.get<std::string>()) == std::end(k_types))
      throw DataError("type: expected \"state-space\", \"polynomial\" or \"augmented\", found " + detail::describe_json_value(t));
    file.type = t.get<std::string>();
  }
  const std::string sub_key = sub_object_key(file.type);
  if (sub_key.empty()) {
    read_state_space_part(root, "", file);
  } else {
    if (!root.contains(sub_key))
      throw DataError("missing required key '" + sub_key + "' (the state-space form of the " + file.type + " model)");
    const json& sub = root[sub_key];
    if (!sub.is_object()) throw DataError(sub_key + ": expected an object {...}, found " + detail::describe_json_value(sub));
    read_state_space_part(sub, sub_key + ".", file);
    json sub_extra = json::object();
    for (const auto& [key, value] : sub.items())
      if (!state_space_keys().count(key)) sub_extra[key] = value;
    if (!sub_extra.empty()) file.extra[sub_key] = std::move(sub_extra);
  }

  const Eigen::Index m = file.model.inputs(), l = file.model.outputs();
  if (root.contains("input_offset")) {
    file.input_offset = vector_from_json(root["input_offset"], "input_offset");
    expect_size(file.input_offset, m, "input_offset", "input");
  }
  if (root.contains("output_offset")) {
    file.output_offset = vector_from_json(root["output_offset"], "output_offset");
    expect_size(file.output_offset, l, "output_offset", "output");
  }
  if (root.contains("provenance")) {
    if (!root["provenance"].is_object())
      throw DataError("provenance: expected an object {...}, found " + detail::describe_json_value(root["provenance"]));
    file.provenance = root["provenance"];
  }

  for (const auto& [key, value] : root.items()) {
    const bool known = top_level_keys().count(key) || (sub_key.empty() ? state_space_keys().count(key) > 0 : key == sub_key);
    if (!known) file.extra[key] = value;
  }
  return file;
}

/// nlohmann reports the byte offset of the last character it read; turn it into
/// the 1-based line:column an editor shows.
std::pair<long, long> line_column(const std::string& text, std::size_t byte) {
  const std::size_t idx = std::min(byte == 0 ? 0 : byte - 1, text.size());
  long line = 1;
  std::size_t line_start = 0;
  for (std::size_t i = 0; i < idx; ++i)
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  return {line, static_cast<long>(idx - line_start + 1)};
}

/// Deepest nesting of arrays and objects a sysid JSON file may have. A model file
/// needs 4 levels (object, sub-object, matrix, row); free-form keys get far more.
/// nlohmann parses iteratively but copies, compares and prints recursively, so a
/// file of 100000 '[' would overflow the stack when its value is kept in extra.
constexpr long k_max_json_depth = 512;

/// Byte offset of the first bracket that opens level k_max_json_depth + 1, or npos.
/// Brackets inside strings do not count; the scan does not validate (the parser does).
std::size_t too_deep_at(const std::string& text) {
  long depth = 0;
  bool in_string = false, escaped = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > k_max_json_depth) return i;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return std::string::npos;
}

// ---- writing -----------------------------------------------------------------

void check_finite(const Eigen::MatrixXd& m, const char* key) {
  if (!m.allFinite())
    throw std::invalid_argument(std::string("model_to_json: ") + key + " contains NaN or Inf (JSON cannot hold them)");
}

void check_shape(const Eigen::MatrixXd& m, Eigen::Index rows, Eigen::Index cols, const char* key) {
  if (m.size() == 0) return;  // absent
  if (m.rows() != rows || m.cols() != cols)
    throw std::invalid_argument(std::string("model_to_json: ") + key + " must be " + std::to_string(rows) + "x" +
                                std::to_string(cols) + ", is " + std::to_string(m.rows()) + "x" +
                                std::to_string(m.cols()));
  check_finite(m, key);
}

json vector_to_json(const Eigen::VectorXd& v) {
  json j = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) j.push_back(v(i));
  return j;
}

using nlohmann::ordered_json;

/// Appends the state-space keys in the documented order (ordered_json keeps
/// insertion order; nlohmann::json would sort them alphabetically).
void add_state_space_part(ordered_json& out, const ModelFile& f) {
  const StateSpace& ss = f.model;
  out["Ts"] = ss.Ts;
  out["A"] = matrix_to_json(ss.A);
  out["B"] = matrix_to_json(ss.B);
  out["C"] = matrix_to_json(ss.C);
  out["D"] = matrix_to_json(ss.D);
  if (f.K.size()) out["K"] = matrix_to_json(f.K);
  if (f.noise_covariance.size()) out["noise_covariance"] = matrix_to_json(f.noise_covariance);
  if (f.x0.size()) out["x0"] = vector_to_json(f.x0);
  if (!ss.input_names.empty()) out["inputs"] = ss.input_names;
  if (!ss.output_names.empty()) out["outputs"] = ss.output_names;
}

/// Pretty printer: like dump(2), but a list of plain values stays on one line, so
/// a matrix is one row per line instead of one number per line. Scalars and keys
/// are written by nlohmann's dump (escaping, shortest round-trip doubles).
void print(std::string& out, const ordered_json& j, int indent) {
  const std::string pad(static_cast<std::size_t>(indent + 2), ' ');
  const std::string close_pad(static_cast<std::size_t>(indent), ' ');
  if (j.is_object() && !j.empty()) {
    out += "{\n";
    bool first = true;
    for (const auto& [key, value] : j.items()) {
      out += first ? "" : ",\n";
      first = false;
      out += pad + ordered_json(key).dump() + ": ";
      print(out, value, indent + 2);
    }
    out += "\n" + close_pad + "}";
  } else if (j.is_array() && !j.empty()) {
    const bool flat = std::all_of(j.begin(), j.end(), [](const ordered_json& e) { return e.is_primitive(); });
    if (flat) {
      out += "[";
      for (std::size_t i = 0; i < j.size(); ++i) out += (i ? ", " : "") + j[i].dump();
      out += "]";
      return;
    }
    out += "[\n";
    for (std::size_t i = 0; i < j.size(); ++i) {
      out += (i ? ",\n" : "") + pad;
      print(out, j[i], indent + 2);
    }
    out += "\n" + close_pad + "]";
  } else {
    out += j.dump();
  }
}

}  // namespace

json matrix_to_json(const Eigen::MatrixXd& m) {
  if (!m.allFinite()) throw std::invalid_argument("matrix_to_json: NaN or Inf cannot be written to JSON");
  json j = json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    json row = json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    j.push_back(std::move(row));
  }
  return j;
}

Eigen::MatrixXd matrix_from_json(const json& j, const std::string& key) {
  const std::string expected = key + ": expected a list of rows, each a list of numbers ([[1, 2], [3, 4]])";
  if (!j.is_array()) throw DataError(expected + ", found " + detail::describe_json_value(j));
  const auto rows = static_cast<Eigen::Index>(j.size());
  if (rows == 0) return Eigen::MatrixXd(0, 0);
  if (!j[0].is_array()) throw DataError(expected + ", found " + detail::describe_json_value(j[0]) + " as row 1");
  const auto cols = static_cast<Eigen::Index>(j[0].size());
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const json& row = j[static_cast<std::size_t>(r)];
    if (!row.is_array()) throw DataError(expected + ", found " + detail::describe_json_value(row) + " as row " + std::to_string(r + 1));
    if (static_cast<Eigen::Index>(row.size()) != cols)
      throw DataError(key + ": row " + std::to_string(r + 1) + " has " + std::to_string(row.size()) +
                      " numbers, row 1 has " + std::to_string(cols));
    for (Eigen::Index c = 0; c < cols; ++c) {
      const json& e = row[static_cast<std::size_t>(c)];
      const std::string where = "entry (" + std::to_string(r + 1) + "," + std::to_string(c + 1) + ")";
      if (!e.is_number()) throw DataError(key + ": " + where + " is not a number (found " + detail::describe_json_value(e) + ")");
      m(r, c) = e.get<double>();
      if (!std::isfinite(m(r, c))) throw DataError(key + ": " + where + " is NaN or Inf");
    }
  }
  return m;
}

nlohmann::ordered_json model_to_ordered_json(const ModelFile& f) {
  if (std::find(std::begin(k_types), std::end(k_types), f.type) == std::end(k_types))
    throw std::invalid_argument("model_to_json: type must be \"state-space\", \"polynomial\" or \"augmented\", is \"" +
                                f.type + "\"");
  f.model.validate();
  const Eigen::Index n = f.model.order(), m = f.model.inputs(), l = f.model.outputs();
  check_shape(f.K, n, l, "K");
  check_shape(f.noise_covariance, l, l, "noise_covariance");
  check_shape(f.x0, f.x0.size() ? n : 0, 1, "x0");
  check_shape(f.input_offset, f.input_offset.size() ? m : 0, 1, "input_offset");
  check_shape(f.output_offset, f.output_offset.size() ? l : 0, 1, "output_offset");
  if (!f.provenance.is_object()) throw std::invalid_argument("model_to_json: provenance must be a JSON object");
  if (!f.extra.is_object()) throw std::invalid_argument("model_to_json: extra must be a JSON object");

  const std::string sub_key = sub_object_key(f.type);
  for (const auto& [key, value] : f.extra.items()) {
    const bool clash = top_level_keys().count(key) || (sub_key.empty() ? state_space_keys().count(key) > 0 : false);
    if (clash) throw std::invalid_argument("model_to_json: extra key '" + key + "' is a key of the model format itself");
    if (!sub_key.empty() && key == sub_key) {
      if (!value.is_object())
        throw std::invalid_argument("model_to_json: extra['" + sub_key + "'] (unknown keys of the sub-object) must be an object");
      for (const auto& [k2, v2] : value.items())
        if (state_space_keys().count(k2))
          throw std::invalid_argument("model_to_json: extra['" + sub_key + "'] key '" + k2 + "' is a state-space key");
    }
  }

  ordered_json top = ordered_json::object();
  top["type"] = f.type;
  if (sub_key.empty()) {
    add_state_space_part(top, f);
  } else {
    for (const auto& [key, value] : f.extra.items())
      if (key != sub_key) top[key] = ordered_json(value);
    ordered_json sub = ordered_json::object();
    add_state_space_part(sub, f);
    if (f.extra.contains(sub_key))
      for (const auto& [key, value] : f.extra[sub_key].items()) sub[key] = ordered_json(value);
    top[sub_key] = std::move(sub);
  }
  if (f.input_offset.size()) top["input_offset"] = vector_to_json(f.input_offset);
  if (f.output_offset.size()) top["output_offset"] = vector_to_json(f.output_offset);
  if (!f.provenance.empty()) top["provenance"] = ordered_json(f.provenance);
  if (sub_key.empty())
    for (const auto& [key, value] : f.extra.items()) top[key] = ordered_json(value);
  return top;
}

std::string pretty_json(const nlohmann::ordered_json& value) {
  std::string out;
  print(out, value, 0);
  out += "\n";
  return out;
}

std::string model_to_json_string(const ModelFile& f) { return pretty_json(model_to_ordered_json(f)); }

nlohmann::json parse_json_text(const std::string& text, const std::string& source_name) {
  if (const std::size_t at = too_deep_at(text); at != std::string::npos) {
    const auto [line, column] = line_column(text, at + 1);
    throw DataError(source_name, line, column,
                    "invalid JSON: lists and objects nested more than " + std::to_string(k_max_json_depth) + " deep");
  }
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    const auto [line, column] = line_column(text, e.byte);
    // nlohmann's text is "[json.exception.parse_error.101] parse error at line L,
    // column C: <reason>"; keep only the reason, the position is in the prefix.
    std::string reason = e.what();
    const auto pos = reason.find(": ", reason.find("parse error"));
    if (pos != std::string::npos) reason = reason.substr(pos + 2);
    throw DataError(source_name, line, column, "invalid JSON: " + reason);
  } catch (const json::exception& e) {
    // E.g. out_of_range.406 "number overflow parsing '1e999'": no position known.
    std::string reason = e.what();
    const auto pos = reason.find("] ");
    if (pos != std::string::npos) reason = reason.substr(pos + 2);
    throw DataError(source_name, 0, 0, "invalid JSON: " + reason);
  }
}

ModelFile model_from_json_string(const std::string& text, const std::string& source_name) {
  return model_from_json_value(parse_json_text(text, source_name), source_name);
}

ModelFile model_from_json_value(const nlohmann::json& root, const std::string& source_name) {
  try {
    return model_from_root(root);
  } catch (const DataError& e) {
    if (!e.file().empty()) throw;
    throw DataError(source_name, 0, 0, e.message());
  }
}

ModelFile read_model_json(const std::string& path) { return model_from_json_string(read_whole_file(path), path); }

void write_model_json(const std::string& path, const ModelFile& file) {
  write_file_atomically(path, model_to_json_string(file));
}

nlohmann::json json_list_or_null(const Eigen::VectorXd& values) {
  nlohmann::json list = nlohmann::json::array();
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    if (std::isfinite(values(i)))
      list.push_back(values(i));
    else
      list.push_back(nullptr);
  }
  return list;
}

StateSpace named_model(const ModelFile& file) {
  StateSpace s = file.model;
  s.input_names = s.input_names_or_defaults();
  s.output_names = s.output_names_or_defaults();
  return s;
}

}  // namespace sysid
