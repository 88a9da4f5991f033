// Implementation of io/family_manifest.hpp (format in the header).
#include <sysid/io/family_manifest.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/io/atomic_file.hpp>

#include <fast_float/fast_float.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace sysid {

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

/// Fields of one line with their 1-based starting columns.
std::vector<std::pair<std::string, long>> split_fields(const std::string& line, const std::string& path, long line_number) {
  std::vector<std::pair<std::string, long>> fields;
  std::size_t k = 0;
  for (;;) {
    while (k < line.size() && (line[k] == ' ' || line[k] == '\t')) ++k;
    const long column = static_cast<long>(k) + 1;
    std::string field;
    if (k < line.size() && line[k] == '"') {
      ++k;
      for (;;) {
        if (k >= line.size()) throw DataError(path, line_number, column, "a quoted field is not closed; close it with '\"'");
        if (line[k] == '"') {
          if (k + 1 < line.size() && line[k + 1] == '"') {
            field += '"';
            k += 2;
            continue;
          }
          ++k;
          break;
        }
        field += line[k++];
      }
      while (k < line.size() && line[k] != ',') {
        if (line[k] != ' ' && line[k] != '\t' && line[k] != '\r')
          throw DataError(path, line_number, static_cast<long>(k) + 1,
                          "text after a quoted field; put the whole field in quotes");
        ++k;
      }
    } else {
      const std::size_t end = line.find(',', k);
      field = trim(line.substr(k, end == std::string::npos ? std::string::npos : end - k));
      k = end == std::string::npos ? line.size() : end;
    }
    fields.emplace_back(field, column);
    if (k >= line.size()) break;
    ++k;  // the comma
  }
  return fields;
}

bool read_number(const std::string& text, double& value) {
  if (text.empty()) return false;
  const char* end = text.data() + text.size();
  const auto r = fast_float::from_chars(text.data(), end, value);
  return r.ec == std::errc() && r.ptr == end && std::isfinite(value);
}

}  // namespace

FamilyManifest read_family_manifest(const std::string& path) {
  const std::string text = read_whole_file(path);
  FamilyManifest m;
  m.path = path;
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::istringstream in(text);
  std::string line;
  long line_number = 0;
  std::vector<std::string> header;
  int log_column = -1, validate_column = -1;
  std::vector<int> condition_columns;
  std::vector<std::vector<std::string>> condition_text;
  std::vector<long> row_lines;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const auto fields = split_fields(line, path, line_number);
    if (header.empty()) {
      for (std::size_t c = 0; c < fields.size(); ++c) {
        const std::string& name = fields[c].first;
        if (name.empty()) throw DataError(path, line_number, fields[c].second, "an empty column name; name every column");
        if (std::find(header.begin(), header.end(), name) != header.end())
          throw DataError(path, line_number, fields[c].second, "column '" + name + "' appears twice; rename one");
        header.push_back(name);
        if (name == "log")
          log_column = static_cast<int>(c);
        else if (name == "validate")
          validate_column = static_cast<int>(c);
        else
          condition_columns.push_back(static_cast<int>(c));
      }
      if (log_column < 0)
        throw DataError(path, line_number, 1,
                        "no 'log' column in the header; the manifest needs a column 'log' naming each experiment's CSV log");
      condition_text.resize(condition_columns.size());
      continue;
    }
    if (fields.size() != header.size())
      throw DataError(path, line_number, fields.back().second,
                      "expected " + std::to_string(header.size()) + " fields as in the header, found " +
                          std::to_string(fields.size()));
    FamilyManifestRow row;
    row.line = line_number;
    row.log = fields[static_cast<std::size_t>(log_column)].first;
    if (row.log.empty())
      throw DataError(path, line_number, fields[static_cast<std::size_t>(log_column)].second,
                      "the 'log' field is empty; name the experiment's CSV log");
    row.log_path = (folder / row.log).lexically_normal().string();
    if (validate_column >= 0) {
      row.validate = fields[static_cast<std::size_t>(validate_column)].first;
      if (!row.validate.empty()) row.validate_path = (folder / row.validate).lexically_normal().string();
    }
    for (std::size_t c = 0; c < condition_columns.size(); ++c)
      condition_text[c].push_back(fields[static_cast<std::size_t>(condition_columns[c])].first);
    row_lines.push_back(line_number);
    m.rows.push_back(std::move(row));
  }
  if (header.empty()) throw DataError(path, 1, 1, "the manifest is empty; it needs a header row and one row per experiment");
  if (m.rows.empty()) throw DataError(path, line_number, 1, "the manifest has a header but no experiment rows");
  for (std::size_t c = 0; c < condition_columns.size(); ++c) {
    Condition cond;
    cond.name = header[static_cast<std::size_t>(condition_columns[c])];
    std::vector<double> numbers;
    bool numeric = true;
    for (const std::string& v : condition_text[c]) {
      double x = 0.0;
      numeric = numeric && read_number(v, x);
      numbers.push_back(x);
    }
    for (std::size_t r = 0; r < condition_text[c].size(); ++r) {
      if (numeric)
        cond.values.emplace_back(numbers[r]);
      else
        cond.values.emplace_back(condition_text[c][r]);
    }
    m.conditions.push_back(std::move(cond));
  }
  return m;
}

}  // namespace sysid
