#pragma once
/// @file
/// Purpose: the wording the JSON file readers (model, FE-model and Markov-parameter
/// files) share in their error messages, so each says "expected ..., found ..." the
/// same way and the helpers exist once.
#include <nlohmann/json.hpp>
#include <string>

#include "sysid/core/errors.hpp"

namespace sysid::detail {

/// What a value looks like, for "found ..." in messages: short scalars verbatim
/// (cut at 40 characters), arrays and objects by their JSON type ("a JSON array").
inline std::string describe_json_value(const nlohmann::json& j) {
  if (j.is_structured()) return std::string("a JSON ") + j.type_name();
  std::string s = j.dump();
  if (s.size() > 40) s = s.substr(0, 40) + "...";
  return s;
}

/// A DataError at a key path inside the file ("inputs[2].dof: expected ..."); the
/// caller that knows the file name prefixes it.
[[noreturn]] inline void throw_data_error_at(const std::string& where, const std::string& what) {
  throw DataError(where + ": " + what);
}

}  // namespace sysid::detail
