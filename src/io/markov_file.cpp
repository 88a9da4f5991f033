// Implementation of io/markov_file.hpp.
#include <sysid/core/errors.hpp>
#include <sysid/io/atomic_file.hpp>
#include "io/detail/json_messages.hpp"
#include <sysid/io/markov_file.hpp>

#include <fstream>
#include <sstream>

namespace sysid {

namespace {

nlohmann::json matrix_json(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(std::move(row));
  }
  return rows;
}

Eigen::MatrixXd matrix_from(const nlohmann::json& j, const std::string& path, const std::string& name) {
  if (!j.is_array() || j.empty() || !j.front().is_array()) detail::throw_data_error_at(path, name + ": expected a list of rows of numbers");
  const std::size_t rows = j.size(), cols = j.front().size();
  Eigen::MatrixXd m(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  for (std::size_t r = 0; r < rows; ++r) {
    if (!j[r].is_array() || j[r].size() != cols)
      detail::throw_data_error_at(path, name + ": expected " + std::to_string(rows) + " rows of " + std::to_string(cols) + " numbers, row " +
                     std::to_string(r + 1) + " differs");
    for (std::size_t c = 0; c < cols; ++c) {
      if (!j[r][c].is_number()) detail::throw_data_error_at(path, name + ": row " + std::to_string(r + 1) + " column " + std::to_string(c + 1) + " is not a number");
      m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = j[r][c].get<double>();
    }
  }
  return m;
}

}  // namespace

void write_markov_file(const std::string& path, const MarkovFile& file) {
  file.markov.validate();
  nlohmann::json j;
  j["type"] = "markov";
  j["Ts"] = file.markov.Ts;
  nlohmann::json inputs = nlohmann::json::array(), outputs = nlohmann::json::array();
  for (Eigen::Index k = 0; k < file.markov.inputs(); ++k) inputs.push_back(file.markov.input_name(k));
  for (Eigen::Index k = 0; k < file.markov.outputs(); ++k) outputs.push_back(file.markov.output_name(k));
  j["inputs"] = inputs;
  j["outputs"] = outputs;
  nlohmann::json h = nlohmann::json::array();
  for (const auto& m : file.markov.h) h.push_back(matrix_json(m));
  j["markov"] = std::move(h);
  j["provenance"] = file.provenance;
  std::ostringstream text;
  text.precision(17);
  // nlohmann's dump uses the shortest round-trip representation of each double.
  text << j.dump(1) << "\n";
  write_file_atomically(path, text.str());
}

MarkovFile read_markov_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) detail::throw_data_error_at(path, "cannot open the file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    detail::throw_data_error_at(path, std::string("invalid JSON: ") + e.what());
  }
  if (!j.is_object() || j.value("type", std::string()) != "markov")
    detail::throw_data_error_at(path, "expected a Markov-parameter file (\"type\": \"markov\", written by sysid lms or sysid okid)");
  MarkovFile f;
  if (!j.contains("Ts") || !j["Ts"].is_number()) detail::throw_data_error_at(path, "Ts: expected a number");
  f.markov.Ts = j["Ts"].get<double>();
  if (!j.contains("markov") || !j["markov"].is_array() || j["markov"].empty()) detail::throw_data_error_at(path, "markov: expected a non-empty list of matrices");
  for (std::size_t k = 0; k < j["markov"].size(); ++k)
    f.markov.h.push_back(matrix_from(j["markov"][k], path, "markov[" + std::to_string(k) + "]"));
  try {
    if (j.contains("inputs")) f.markov.input_names = j["inputs"].get<std::vector<std::string>>();
    if (j.contains("outputs")) f.markov.output_names = j["outputs"].get<std::vector<std::string>>();
  } catch (const nlohmann::json::exception&) {
    detail::throw_data_error_at(path, "inputs/outputs: expected lists of names");
  }
  if (j.contains("provenance")) f.provenance = j["provenance"];
  try {
    f.markov.validate();
  } catch (const std::invalid_argument& e) {
    detail::throw_data_error_at(path, e.what());
  }
  return f;
}

}  // namespace sysid
