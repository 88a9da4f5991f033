#pragma once
/// @file
/// Purpose: MATLAB files out (DESIGN.md "Model families", `sysid export --mat`):
/// MAT v5 files written and read through libmatio, so that MATLAB, Octave and
/// scipy.io.loadmat take a model as `ss(A, B, C, D, Ts)` needs it.
///
/// Variables are real double matrices (column-major, as MATLAB stores them, so an
/// Eigen matrix is written without reordering) or column cell arrays of strings
/// (UTF-8 char arrays; InputName and OutputName). A file is written atomically:
/// to a temporary name in the same folder, renamed when complete, so a failed
/// write leaves no half-written file.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "sysid/io/model_json.hpp"

namespace sysid {

struct MatVariable {
  std::string name;
  Eigen::MatrixXd values;            ///< a real matrix (used when `strings` is empty and not is_strings)
  std::vector<std::string> strings;  ///< a cell column of strings (is_strings)
  bool is_strings = false;

  static MatVariable matrix(std::string name, Eigen::MatrixXd values) { return {std::move(name), std::move(values), {}, false}; }
  static MatVariable cell_of_strings(std::string name, std::vector<std::string> strings) {
    return {std::move(name), {}, std::move(strings), true};
  }
};

/// Writes `variables` as a MAT v5 file (uncompressed). Errors: sysid::DataError
/// naming the file when it cannot be created or written; std::invalid_argument for
/// a name MATLAB refuses (a letter, then letters, digits and '_', at most 63
/// characters). NaN and Inf are MATLAB values and are written as they are.
void write_mat_file(const std::string& path, const std::vector<MatVariable>& variables);

/// Reads every real double matrix and every cell array of strings of a MAT file
/// (other classes are skipped). Errors: sysid::DataError naming the file.
std::vector<MatVariable> read_mat_file(const std::string& path);

/// The variables of a model file (DESIGN.md "`sysid export --mat`"): A, B, C, D, Ts
/// and, where present, K, x0, InputName, OutputName; vectors as columns.
std::vector<MatVariable> model_mat_variables(const ModelFile& file);

}  // namespace sysid
