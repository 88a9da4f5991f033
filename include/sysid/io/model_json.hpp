#pragma once
/// @file
/// Purpose: model files in JSON (DESIGN.md "Model files"), read and written so that
/// every number round-trips bit-exactly and every key the tool does not know is
/// kept.
///
/// Layout written (keys in this order, 2-space indent, one matrix row per line):
///
///   "state-space": type, Ts, A, B, C, D, [K], [noise_covariance], [x0],
///                  [inputs], [outputs], [input_offset], [output_offset],
///                  [provenance], then the extra keys.
///   "polynomial":  type, the extra keys (the coefficient lists A, B, C, F, nk,
///                  kept verbatim), "state_space": {Ts, A, B, C, D, [K],
///                  [noise_covariance], [x0], [inputs], [outputs]}, offsets,
///                  provenance.
///   "augmented":   the same with the sub-object under "nominal" (the rest of the
///                  augmented format — blocks and connections — lives in extra).
///
/// For "polynomial"/"augmented", unknown keys inside the sub-object are kept in
/// extra["state_space"] / extra["nominal"] (an object) and written back into it.
///
/// Matrices are row-major nested lists ([[a11, a12], [a21, a22]]), vectors flat
/// lists. A matrix with zero rows is written [] (a model with no states has
/// B = [] and C = [[], ...]; on reading, the zero dimensions are restored from D).
/// Numbers are written by nlohmann::json's dump (Grisu2: the shortest digit string
/// that reads back to the same double, at most 17 significant digits) and read with
/// a correctly rounded strtod, hence bit-exact round trips. JSON has no NaN/Inf: a
/// model containing them is refused on write (std::invalid_argument) and on read
/// (DataError; so is a number too large for a double, such as 1e999).
#include <Eigen/Dense>
#include <nlohmann/json.hpp>
#include <string>

#include "sysid/core/state_space.hpp"

namespace sysid {

struct ModelFile {
  std::string type = "state-space";  ///< "state-space" | "polynomial" | "augmented"
  StateSpace model;                  ///< for "polynomial": the "state_space" sub-object; "augmented": "nominal"
  Eigen::MatrixXd K;                 ///< n x l Kalman gain (innovation form); empty when absent
  Eigen::MatrixXd noise_covariance;  ///< l x l innovation covariance; empty when absent
  Eigen::VectorXd x0;                ///< n initial state; empty when absent
  Eigen::VectorXd input_offset;      ///< m means removed from the inputs; empty when absent
  Eigen::VectorXd output_offset;     ///< l means removed from the outputs; empty when absent
  nlohmann::json provenance = nlohmann::json::object();  ///< method, order, data, fit ... (free form)
  nlohmann::json extra = nlohmann::json::object();       ///< every other key, kept verbatim (round-tripped)
};

/// The file's state space carrying every channel's name (u1.., y1.. where the file
/// has none; polynomial and augmented files included).
StateSpace named_model(const ModelFile& file);

/// A vector as a JSON list, NaN and Inf written as null (JSON has no number for
/// them: an order that failed in a sweep has a NaN fit).
nlohmann::json json_list_or_null(const Eigen::VectorXd& values);

/// Pretty-printed JSON text (2-space indent, matrix rows on one line each).
/// Preconditions (std::invalid_argument): model.validate() passes; K is n x l,
/// noise_covariance l x l, x0 n, offsets m and l (or empty); all finite; type is one
/// of the three; extra and provenance are objects and extra has no key that the
/// format itself uses.
std::string model_to_json_string(const ModelFile& file);

/// The model as a JSON object, keys in the documented order (what
/// model_to_json_string prints); the same preconditions. For files that hold
/// models inside them (a family's members, io/family_file.hpp).
nlohmann::ordered_json model_to_ordered_json(const ModelFile& file);

/// The house's pretty printing of any JSON value (2-space indent, a list of plain
/// values on one line, so a matrix is one row per line), with a final newline.
std::string pretty_json(const nlohmann::ordered_json& value);

/// A model from a parsed JSON object (a model file's root, or a model object
/// inside another file); the errors of model_from_json_string, naming `source_name`.
ModelFile model_from_json_value(const nlohmann::json& root, const std::string& source_name);

/// Parses model JSON text; `source_name` stands for the file name in messages.
/// Errors: sysid::DataError (file = source_name) for invalid JSON (with line and
/// column), a missing required key (Ts, A, B, C, D), a malformed or mis-sized value
/// ("A: expected a list of 3 rows of 3 numbers, found 3 rows of 2"), NaN/Inf, a
/// model whose dimensions do not fit together.
ModelFile model_from_json_string(const std::string& text, const std::string& source_name);

/// Purpose: parse JSON text for any sysid file reader. Errors: sysid::DataError
/// naming `source_name` and the 1-based line:column of a syntax error (nlohmann
/// reports a byte offset) or of the bracket that nests lists and objects more
/// than 512 deep (deeper values would overflow the stack when copied or
/// printed), or no position for e.g. a number overflow.
nlohmann::json parse_json_text(const std::string& text, const std::string& source_name);

/// read_whole_file + model_from_json_string (DataError also for an unreadable file).
ModelFile read_model_json(const std::string& path);

/// model_to_json_string written with write_file_atomically.
void write_model_json(const std::string& path, const ModelFile& file);

/// Row-major nested list. Throws std::invalid_argument on NaN/Inf (JSON has no
/// representation for them; nlohmann would silently write null).
nlohmann::json matrix_to_json(const Eigen::MatrixXd& m);

/// Inverse of matrix_to_json: a list of equally long lists of numbers. Throws
/// sysid::DataError (message only, no file) prefixed with `key_for_messages`
/// ("A: row 2 has 2 numbers, row 1 has 3").
Eigen::MatrixXd matrix_from_json(const nlohmann::json& j, const std::string& key_for_messages);

}  // namespace sysid
