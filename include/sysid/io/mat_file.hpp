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

#include "sysid/io/family_file.hpp"
#include "sysid/io/model_json.hpp"

namespace sysid {

/// One element of a general cell array: a real matrix or a text.
struct MatCellElement {
  Eigen::MatrixXd values;
  std::string text;
  bool is_text = false;
};

struct MatVariable {
  std::string name;
  Eigen::MatrixXd values;            ///< a real matrix (used when `strings` is empty and not is_strings)
  std::vector<std::string> strings;  ///< a cell column of strings (is_strings)
  bool is_strings = false;
  /// An N-D real array (N >= 3) when not empty: its dimensions, with `values`
  /// holding it column-major as dims[0] x (dims[1] * dims[2] * ...).
  std::vector<std::size_t> dims;
  /// A general cell array (is_cell): cell_rows x cell_cols elements, column-major.
  std::vector<MatCellElement> cell;
  std::size_t cell_rows = 0, cell_cols = 0;
  bool is_cell = false;

  static MatVariable matrix(std::string name, Eigen::MatrixXd values) { return {std::move(name), std::move(values), {}, false, {}, {}, 0, 0, false}; }
  static MatVariable cell_of_strings(std::string name, std::vector<std::string> strings) {
    return {std::move(name), {}, std::move(strings), true, {}, {}, 0, 0, false};
  }
  /// An N-D array from its slices: slices[k] is the (:, :, k) page (all the same size).
  static MatVariable pages(std::string name, const std::vector<Eigen::MatrixXd>& slices);
  static MatVariable cell_array(std::string name, std::size_t rows, std::size_t cols, std::vector<MatCellElement> elements) {
    return {std::move(name), {}, {}, false, {}, std::move(elements), rows, cols, true};
  }
};

/// Writes `variables` as a MAT v5 file (uncompressed). Errors: sysid::DataError
/// naming the file when it cannot be created or written; std::invalid_argument for
/// a name MATLAB refuses (a letter, then letters, digits and '_', at most 63
/// characters). NaN and Inf are MATLAB values and are written as they are.
void write_mat_file(const std::string& path, const std::vector<MatVariable>& variables);

/// Reads every real double array (N-D ones with `dims`) and every cell array of a
/// MAT file (a cell whose elements are all texts as `strings`, else as `cell`;
/// other classes are skipped). Errors: sysid::DataError naming the file.
std::vector<MatVariable> read_mat_file(const std::string& path);

/// The variables of a model file (DESIGN.md "`sysid export --mat`"): A, B, C, D, Ts
/// and, where present, K, x0, InputName, OutputName; vectors as columns.
std::vector<MatVariable> model_mat_variables(const ModelFile& file);

/// The variables of a family file (DESIGN.md "`sysid export --mat`"): the nominal's
/// A B C D Ts (K, x0, InputName, OutputName where present); A_members, B_members,
/// C_members, D_members as n x n x N ... arrays when every member has one order,
/// else N x 1 cell arrays of the same names; A_nominal ... D_nominal; A_weight ...
/// D_weight (when there is a weight); frequency_hz and bound (columns);
/// conditions (N x c cell of numbers and labels) with condition_names (c x 1);
/// fit_percent (N x outputs); mode_freq_hz and mode_damping (N x modes, NaN where
/// a member lacks the mode).
std::vector<MatVariable> family_mat_variables(const FamilyFile& family);

}  // namespace sysid
