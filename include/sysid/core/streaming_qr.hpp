#pragma once
/// @file
/// Purpose: the R factor of a tall matrix that arrives in blocks of rows,
/// without ever holding the whole matrix: memory O(k^2 + chunk*k) for k columns.
///
/// Method: after each full chunk, the Householder QR of [R; chunk] replaces R
/// (Golub & Van Loan, "Matrix Computations", 4th ed., sec. 5.2 and the
/// updating discussion of sec. 6.5). Because the Q factors are orthogonal, the
/// final R equals (up to row signs) the R of the QR factorisation of the full
/// matrix, and R^T R equals its Gram matrix, with the backward stability of
/// Householder QR rather than the squared condition number of the normal equations.
///
/// Numerical aspects: cost about 2 N k^2 flops for N rows; the chunk is sized
/// so that the QR works on tall blocks (BLAS-3 friendly).
#include <Eigen/Dense>
#include <algorithm>
#include <stdexcept>

namespace sysid {

class StreamingQR {
 public:
  /// @param columns      number of columns k of the tall matrix (> 0)
  /// @param chunk_rows   rows buffered before each update (default 4k, at least 256)
  explicit StreamingQR(Eigen::Index columns, Eigen::Index chunk_rows = 0)
      : m_columns(columns), m_r(Eigen::MatrixXd::Zero(columns, columns)) {
    if (columns <= 0) throw std::invalid_argument("StreamingQR: need columns > 0");
    const Eigen::Index chunk = chunk_rows > 0 ? chunk_rows : std::max<Eigen::Index>(256, 4 * columns);
    m_buffer.resize(columns + chunk, columns);
    m_buffer.topRows(columns).setZero();
    m_fill = 0;
  }

  /// Appends rows (any number, each with `columns` entries).
  template <class Derived>
  void add_rows(const Eigen::MatrixBase<Derived>& rows) {
    if (rows.cols() != m_columns) throw std::invalid_argument("StreamingQR: row block has the wrong number of columns");
    Eigen::Index done = 0;
    while (done < rows.rows()) {
      const Eigen::Index room = chunk_capacity() - m_fill;
      const Eigen::Index take = std::min(room, rows.rows() - done);
      m_buffer.middleRows(m_columns + m_fill, take) = rows.middleRows(done, take);
      m_fill += take;
      done += take;
      m_rows += take;
      if (m_fill == chunk_capacity()) flush();
    }
  }

  /// Direct access to a block of `count` rows to fill in place (avoids a copy);
  /// call commit_rows(count) afterwards. count must not exceed free_rows().
  Eigen::Index free_rows() const { return chunk_capacity() - m_fill; }
  auto next_rows(Eigen::Index count) { return m_buffer.middleRows(m_columns + m_fill, count); }
  void commit_rows(Eigen::Index count) {
    m_fill += count;
    m_rows += count;
    if (m_fill == chunk_capacity()) flush();
  }

  /// Upper-triangular R (k x k) with non-negative diagonal, such that
  /// R^T R = M^T M for all rows M added so far.
  Eigen::MatrixXd r() {
    flush();
    Eigen::MatrixXd r = m_r;
    for (Eigen::Index i = 0; i < r.rows(); ++i)
      if (r(i, i) < 0) r.row(i) *= -1.0;
    return r;
  }

  Eigen::Index rows_added() const { return m_rows; }

 private:
  Eigen::Index chunk_capacity() const { return m_buffer.rows() - m_columns; }

  void flush() {
    if (m_fill == 0) return;
    const Eigen::Index rows = m_columns + m_fill;
    m_buffer.topRows(m_columns) = m_r;
    Eigen::Ref<Eigen::MatrixXd> stacked(m_buffer.topRows(rows));
    Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(stacked);  // in place: no copy of the chunk
    m_r = qr.matrixQR().topRows(std::min(rows, m_columns)).template triangularView<Eigen::Upper>();
    m_fill = 0;
  }

  Eigen::Index m_columns;
  Eigen::MatrixXd m_r;
  Eigen::MatrixXd m_buffer;  // first k rows hold R during an update, then the chunk
  Eigen::Index m_fill = 0;
  Eigen::Index m_rows = 0;
};

}  // namespace sysid
