#pragma once
/// @file
/// Purpose: sparse matrices in the NIST Matrix Market exchange format, the format
/// finite-element packages (ANSYS, Abaqus, Code_Aster, FEniCS, MATLAB's mmwrite)
/// export mass, stiffness and damping matrices in.
///
/// Method: R. F. Boisvert, R. Pozo, K. Remington, "The Matrix Market Exchange
/// Formats: Initial Design", NISTIR 5935 (1996). Accepted:
///
///   %%MatrixMarket matrix coordinate real|integer general|symmetric
///   % comment lines (anywhere after the banner) and blank lines are skipped
///   M N NNZ                  <- size line (coordinate)
///   i j value                <- NNZ entries, 1-based indices, one per line
///
///   %%MatrixMarket matrix array real|integer general|symmetric
///   M N                      <- size line (array)
///   value                    <- dense, column-major, one per line; a symmetric
///                               array holds the lower triangle by columns
///                               (column j: rows j..N), N(N+1)/2 values
///
/// The words after `%%MatrixMarket` are case-insensitive (as the format says);
/// Windows line ends and a UTF-8 byte-order mark are accepted.
///
/// Symmetric storage holds the lower triangle (row >= column); on reading it is
/// expanded to the full matrix, each off-diagonal entry mirrored. Duplicate
/// coordinate entries are SUMMED, not rejected: FE exporters write the element
/// contributions unassembled (one entry per element sharing a DOF pair), and the
/// sum is the assembled matrix. Explicitly listed zeros (coordinate format) stay
/// stored entries, so the sparsity pattern and the sign of -0.0 round-trip; zeros
/// of the array format are not stored.
///
/// Numerical aspects: numbers are read with fast_float (correctly rounded, like
/// strtod) and written with "%.17g", so write-then-read is bit-exact (including
/// subnormals and -0.0). Reading is O(file size + nnz log nnz).
#include <Eigen/SparseCore>
#include <string>

namespace sysid {

/// Purpose: parse Matrix Market text; `source` stands for the file name in messages.
///
/// Returns the full (symmetric storage expanded) matrix, compressed, column-major.
///
/// Errors: sysid::DataError(source, line, column, message) saying what was
/// expected, for: a missing or garbled banner; an unsupported kind (complex,
/// pattern, hermitian, skew-symmetric, vector objects: the message lists the
/// supported ones); a bad size line (non-integer, negative, rows x cols
/// overflowing, a dimension above the sparse index limit 2^31 - 1, NNZ > rows x
/// cols, a non-square symmetric matrix); an index outside 1..rows / 1..cols; an
/// upper-triangle entry in a symmetric file; a value that is not a number (or not
/// an integer in an integer file); NaN or Inf (also overflow such as 1e999); a
/// line with missing or extra fields; fewer entries than announced (reported at
/// the end of the file) or more (reported at the first extra entry).
Eigen::SparseMatrix<double> parse_matrix_market(const std::string& text, const std::string& source);

/// read_whole_file + parse_matrix_market (DataError also for an unreadable file).
Eigen::SparseMatrix<double> read_matrix_market(const std::string& path);

/// True when the matrix is square and A(i,j) == A(j,i) for every i, j (an absent
/// entry counts as 0; +0.0 == -0.0). NaN is never symmetric.
bool is_exactly_symmetric(const Eigen::SparseMatrix<double>& matrix);

/// Purpose: Matrix Market text, `coordinate real general` with every stored entry
/// (explicit zeros included), or with `symmetric` the `coordinate real symmetric`
/// form: only the stored entries with row >= column. Column-major order, 1-based
/// indices, values as "%.17g".
///
/// Preconditions (std::invalid_argument): every entry finite (the reader refuses
/// NaN/Inf); with `symmetric`, is_exactly_symmetric(matrix) — a nearly symmetric
/// matrix would otherwise silently lose its upper triangle.
std::string format_matrix_market(const Eigen::SparseMatrix<double>& matrix, bool symmetric);

/// format_matrix_market written with write_file_atomically (DataError when the
/// file cannot be written; the old file, if any, is then untouched).
void write_matrix_market(const std::string& path, const Eigen::SparseMatrix<double>& matrix, bool symmetric);

}  // namespace sysid
