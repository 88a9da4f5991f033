#pragma once
/// @file
/// Purpose: finite-element model files: a small JSON file that names the mass,
/// stiffness (and damping) matrices, stored beside it in Matrix Market files
/// (io/matrix_market.hpp), and says where the force inputs act and what the
/// sensors read. This is the "simulation model" side of a comparison with
/// measurements (fem/second_order_model.hpp).
///
/// Format:
///
///   {
///     "type": "fem",
///     "mass": "M.mtx", "stiffness": "K.mtx",
///     "damping": {"matrix": "C.mtx"}  |  {"rayleigh": {"alpha": 0.5, "beta": 1e-6}}  |  {"modal_ratio": 0.02},
///     "inputs":  [{"name": "F_tip", "dof": 12, "unit": "N"}],
///     "outputs": [{"name": "a_mid", "dof": 40, "quantity": "acceleration", "unit": "m/s^2"}],
///     "length_unit": "m", "description": "free text"
///   }
///
/// - Required: type (= "fem"), mass, stiffness, inputs, outputs (non-empty lists).
/// - damping: optional (absent = no damping); an object with exactly one of
///   `matrix` (a file name), `rayleigh` (C = alpha M + beta K; alpha in 1/s, beta
///   in s, each optional, default 0) or `modal_ratio` (zeta, dimensionless, >= 0).
/// - inputs[i]: name, dof (required), unit (optional, default "N").
/// - outputs[i]: name, dof, quantity (required: displacement | velocity |
///   acceleration), unit (optional; default <L>, <L>/s, <L>/s^2 by quantity with
///   <L> = length_unit).
/// - length_unit (optional, default "m"): only sets the default output units.
///   description (optional): free text for people; neither is kept in the model.
/// - DOF indices are 0-based rows of the matrices. Matrix file names are relative
///   to the JSON file's directory (absolute names are used as they are).
/// - Unknown keys are refused (at every level), naming the key and the accepted
///   ones: in a physics file a misspelt key ("dampign", "Dof") silently changing
///   the model is worse than an error.
#include <string>

#include "sysid/fem/second_order_model.hpp"

namespace sysid {

/// Purpose: read an FE model file and the Matrix Market files it names.
///
/// Errors: sysid::DataError naming the JSON file (with line and column for invalid
/// JSON) and the key path for a bad value, e.g. "inputs[1].dof: expected a
/// non-negative integer", "damping: expected exactly one of matrix, rayleigh,
/// modal_ratio", "type: expected \"fem\"" (list indices are 0-based). Matrix
/// Market errors propagate unchanged, naming the .mtx file, line and column. The
/// assembled model must pass SecondOrderModel::validate() (square symmetric
/// matrices of one size, DOFs in 0..n-1, unique names ...); a violation becomes a
/// DataError naming the JSON file.
fem::SecondOrderModel read_fem_model(const std::string& json_path);

/// Purpose: write `model` as `json_path` plus `<stem>.M.mtx`, `<stem>.K.mtx` and,
/// for matrix damping, `<stem>.C.mtx` in the same directory (stem = the JSON file
/// name without its extension); the JSON names them relative to itself. Output
/// units are written explicitly; `description` is written when not empty.
///
/// Method: every file is written atomically (io/atomic_file.hpp), the matrices
/// first and the JSON last, so the JSON never names a matrix not yet written.
/// Matrices are stored symmetric (lower triangle) when exactly symmetric; a matrix
/// that validate() accepts as symmetric only within its tolerance is stored in
/// general form, so nothing is altered and reading returns it bit-exactly.
///
/// Preconditions (std::invalid_argument): model.validate() passes. File errors:
/// sysid::DataError naming the file.
void write_fem_model(const std::string& json_path, const fem::SecondOrderModel& model,
                     const std::string& description = "");

}  // namespace sysid
