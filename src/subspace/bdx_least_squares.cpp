// Implementation of subspace/bdx_least_squares.hpp (method and references there).
#include <sysid/subspace/bdx_least_squares.hpp>

#include <sysid/core/real_modal_form.hpp>
#include <sysid/core/flush_subnormals.hpp>
#include <sysid/core/parallel_for.hpp>
#include <sysid/core/streaming_qr.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace sysid {

namespace {

/// x0 regressors below this fraction of their running peak are taken as zero.
constexpr double kNegligibleInitialResponse = 1e-17;
/// Experiments shorter than this are not cut (the cut costs a thread start and a merge).
constexpr Eigen::Index kMinimumSplit = 8192;
/// Share of an experiment's samples in the first piece. The first piece has the
/// rows with x0 regressors (wider rows), the second first runs the recursion
/// alone up to its start. On the Par2 log (order 10, SISO, modal coordinates,
/// 40 000 samples, Gram route) the B/D/x0 step took 1.89, 1.77-1.83, 1.80 and
/// 1.92 ms at shares 0.52, 0.58, 0.62 and 0.66 (min of 60, +-0.05 ms between
/// runs): 0.58 (a split that is off only costs time, never accuracy).
constexpr double kFirstPieceShare = 0.58;

/// The regressors' recursion, one sample at a time, on the transposed state:
/// columns q l .. q l + l - 1 of `state` hold Psi_q^T, the last l columns
/// Lambda^T, and state <- A^T state + [u_q C^T ..., 0].
class Recursion {
 public:
  /// `modal_At` non-null: A^T is block diagonal, A_m^T (modal coordinates),
  /// `At` unused; otherwise the dense `At`.
  Recursion(const Eigen::MatrixXd& At, const ModalBlockLists* modal_At, const Eigen::MatrixXd& Ct, Eigen::Index m)
      : m_At(At), m_modal_At(modal_At), m_Ct(Ct), m_state(Ct.rows(), (m + 1) * Ct.cols()), m_next(m_state.rows(), m_state.cols()) {
    m_state.leftCols(m * Ct.cols()).setZero();
    m_state.rightCols(Ct.cols()) = Ct;
  }

  const Eigen::MatrixXd& state() const { return m_state; }

  /// Whether the current sample's x0 regressors are negligible (and updates their running peak).
  bool initial_response_negligible() {
    const Eigen::Index l = m_Ct.cols(), n = m_state.rows();
    const double* lambda = m_state.data() + (m_state.cols() - l) * n;  // the last l columns, contiguous
    // Eigen's reduction: independent partial maxima, not one serial chain.
    const double response = Eigen::Map<const Eigen::VectorXd>(lambda, n * l).cwiseAbs().maxCoeff();
    m_initial_response_peak = std::max(m_initial_response_peak, response);
    return response <= kNegligibleInitialResponse * m_initial_response_peak;
  }

  template <class Row>
  void advance(const Row& u) {
    const Eigen::Index n = m_state.rows(), l = m_Ct.cols(), m = u.size();
    if (m_modal_At) {
      // Psi_q^T columns: A_m^T psi + u_q c_r (c_r a column of C^T), Lambda^T
      // columns: A_m^T lambda. One pass over the state.
      for (Eigen::Index q = 0; q < m; ++q) {
        const double uq = u(q);
        for (Eigen::Index r = 0; r < l; ++r) {
          const double* c = m_Ct.data() + r * n;
          const Eigen::Index j = q * l + r;
          m_modal_At->product(m_state.data() + j * n, m_next.data() + j * n, [uq, c](Eigen::Index k) { return uq * c[k]; });
        }
      }
      for (Eigen::Index j = m * l; j < m_state.cols(); ++j)
        m_modal_At->product(m_state.data() + j * n, m_next.data() + j * n, [](Eigen::Index) { return 0.0; });
    } else {
      // lazyProduct keeps this small product inline: the general GEMM dispatch
      // costs more than the product itself at these sizes.
      m_next.noalias() = m_At.lazyProduct(m_state);
      const double* ct = m_Ct.data();
      for (Eigen::Index q = 0; q < m; ++q) {
        const double uq = u(q);
        double* psi = m_next.data() + q * l * n;  // Psi_q^T: columns q l .. q l + l - 1, contiguous
        for (Eigen::Index k = 0; k < n * l; ++k) psi[k] += uq * ct[k];
      }
    }
    m_state.swap(m_next);
  }

 private:
  const Eigen::MatrixXd& m_At;
  const ModalBlockLists* m_modal_At;
  const Eigen::MatrixXd& m_Ct;
  Eigen::MatrixXd m_state, m_next;
  double m_initial_response_peak = 0;
};

/// The recursion's system: A^T (dense) or the modal blocks, and C^T, in the
/// coordinates the regression runs in; T maps those back (empty: identity).
struct Coordinates {
  Eigen::MatrixXd At, Ct, T;
  bool modal = false;
  ModalBlockLists modal_At;  ///< A_m^T when modal
  double modal_condition = std::numeric_limits<double>::infinity();
};

Coordinates choose_coordinates(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, double modal_condition_limit) {
  Coordinates c;
  if (auto form = conditioned_real_modal_form(A, modal_condition_limit, c.modal_condition)) {
    c.T = form->T;
    c.modal = true;
    c.modal_At = ModalBlockLists(form->blocks, true);
    c.Ct = (C * form->T).transpose();
  } else {
    c.At = A.transpose();
    c.Ct = C.transpose();
  }
  return c;
}

/// The rows of samples [begin, end) of one experiment, in their own QRs or
/// Gram matrices (lower triangles) of [regressors, y].
struct Piece {
  Eigen::Index experiment = 0, begin = 0, end = 0;
  std::optional<StreamingQR> full, reduced;  ///< rows with and without x0 regressors (QR route)
  Eigen::MatrixXd full_gram, reduced_gram;    ///< the same rows' Gram matrices (Gram route)
  Eigen::Index full_rows = 0, reduced_rows = 0;
};

/// Rows of the regression as they are formed: one sample's entries contiguous.
using RowBuffer = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Hands a block of rows to the piece's QRs or Gram matrices.
void add_rows(Piece& piece, bool gram, const Eigen::Ref<const RowBuffer>& rows, bool full) {
  if (rows.rows() == 0) return;
  if (gram) (full ? piece.full_gram : piece.reduced_gram).selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
  else (full ? piece.full : piece.reduced)->add_rows(rows);
}

void accumulate_piece(const Coordinates& co, const Experiment& ex, Eigen::Index experiments, bool gram, Piece& piece) {
  const Eigen::Index n = co.Ct.rows(), l = co.Ct.cols(), m = ex.u.cols();
  const Eigen::Index input_columns = n * m + l * m;  // B then D: the columns every row has
  const Eigen::Index p = input_columns + n * experiments;
  piece.full_rows = piece.reduced_rows = 0;
  if (gram) {
    piece.full_gram.setZero(p + 1, p + 1);
    piece.reduced_gram.setZero(input_columns + 1, input_columns + 1);
  } else {
    piece.full.emplace(p + 1);
    piece.reduced.emplace(input_columns + 1);
  }
  // The x0 regressors (C A^t) decay through the subnormal range over a long record (core/flush_subnormals.hpp).
  const ScopedFlushSubnormals flush;
  Recursion rec(co.At, co.modal ? &co.modal_At : nullptr, co.Ct, m);
  for (Eigen::Index t = 0; t < piece.begin; ++t) {
    rec.initial_response_negligible();  // keeps the running peak a single pass would have
    rec.advance(ex.u.row(t));
  }
  // Rows of `block` samples are formed together and handed to the QRs or Gram matrices at once,
  // into buffers reused for every block (no allocation per sample).
  const Eigen::Index block = 256;
  RowBuffer rows(block * l, p + 1), reduced_rows(block * l, input_columns + 1);
  for (Eigen::Index start = piece.begin; start < piece.end; start += block) {
    const Eigen::Index count = std::min(block, piece.end - start);
    Eigen::Index full = 0, reduced = 0;  // rows filled in each buffer
    rows.topRows(count * l).setZero();
    reduced_rows.topRows(count * l).setZero();
    for (Eigen::Index k = 0; k < count; ++k) {
      const Eigen::Index t = start + k;
      const bool negligible = rec.initial_response_negligible();
      // Row r of this sample: [Psi_1^T(:, r) .. Psi_m^T(:, r), u(t) at D(r, q), Lambda^T(:, r) unless
      // negligible, y_r(t)]; the state's columns are contiguous, and so are the rows of the buffers.
      RowBuffer& buffer = negligible ? reduced_rows : rows;
      double* row = buffer.data() + (negligible ? reduced : full) * l * buffer.cols();
      (negligible ? reduced : full) += 1;
      const double* state = rec.state().data();
      for (Eigen::Index r = 0; r < l; ++r, row += buffer.cols()) {
        for (Eigen::Index q = 0; q < m; ++q) {
          std::copy_n(state + (q * l + r) * n, n, row + q * n);
          row[n * m + q * l + r] = ex.u(t, q);
        }
        if (!negligible) std::copy_n(state + (m * l + r) * n, n, row + input_columns + piece.experiment * n);
        row[buffer.cols() - 1] = ex.y(t, r);
      }
      rec.advance(ex.u.row(t));
    }
    add_rows(piece, gram, rows.topRows(full * l), true);
    add_rows(piece, gram, reduced_rows.topRows(reduced * l), false);
    piece.full_rows += full;
    piece.reduced_rows += reduced;
  }
}

/// The pieces of every experiment: one, or two cut at kFirstPieceShare.
std::vector<Piece> cut_into_pieces(const IoData& data, Eigen::Index max_samples, Eigen::Index& samples_used) {
  std::vector<Piece> pieces;
  for (std::size_t e = 0; e < data.experiments.size(); ++e) {
    const Eigen::Index samples = std::min(data.experiments[e].samples(), max_samples);
    samples_used += samples;
    const Eigen::Index cut =
        samples >= kMinimumSplit ? static_cast<Eigen::Index>(kFirstPieceShare * static_cast<double>(samples)) : samples;
    const auto experiment = static_cast<Eigen::Index>(e);
    pieces.push_back(Piece{experiment, 0, cut, {}, {}, {}, {}, 0, 0});
    if (cut < samples) pieces.push_back(Piece{experiment, cut, samples, {}, {}, {}, {}, 0, 0});
  }
  return pieces;
}

/// Column norms of a regression from its triangle or Gram diagonal; an
/// all-zero regressor (input constant zero) keeps scale 1 and stays zero.
Eigen::VectorXd safe_column_norms(Eigen::VectorXd squared_norms) {
  for (double& c : squared_norms) c = c > 0.0 ? std::sqrt(c) : 1.0;
  return squared_norms;
}

/// QR route: merges the pieces' triangles in their order (the full ones, then
/// the reduced ones with zeros in every x0 column) and equilibrates.
/// Column equilibration before the rank decision: the regressors' scales can
/// differ by many decades (C A^t and the B regressors grow like rho(A)^t when
/// A is unstable: 1e21 over 600 samples at rho = 1.083), and a rank threshold
/// relative to the largest pivot then discards every other column, B = D = 0.
/// The column norms of R are those of the regression (Q is orthogonal), and
/// R S is the R factor of M S, so scaling after the QR is scaling the data.
void qr_route_triangle(std::vector<Piece>& pieces, Eigen::Index input_columns, Eigen::Index p, Eigen::MatrixXd& r11,
                       Eigen::VectorXd& rhs, Eigen::VectorXd& column_norm) {
  StreamingQR qr(p + 1), reduced_qr(input_columns + 1);
  Eigen::Index reduced_rows = 0;
  for (Piece& piece : pieces) {
    if (piece.full_rows > 0) qr.add_rows(piece.full->r());
    if (piece.reduced_rows > 0) reduced_qr.add_rows(piece.reduced->r());
    reduced_rows += piece.reduced_rows;
  }
  if (reduced_rows > 0) {
    const Eigen::MatrixXd r_reduced = reduced_qr.r();
    Eigen::MatrixXd merged = Eigen::MatrixXd::Zero(r_reduced.rows(), p + 1);
    merged.leftCols(input_columns) = r_reduced.leftCols(input_columns);
    merged.col(p) = r_reduced.col(input_columns);
    qr.add_rows(merged);
  }
  const Eigen::MatrixXd r = qr.r();
  column_norm = safe_column_norms(r.topLeftCorner(p, p).colwise().squaredNorm().transpose());
  r11 = r.topLeftCorner(p, p) * column_norm.cwiseInverse().asDiagonal();
  rhs = r.topRightCorner(p, 1);
}

/// Gram route: sums the pieces' Gram matrices in their order, equilibrates the
/// columns and factorises G_s = S^-1 X^T X S^-1 = r11^T r11, rhs = r11^-T S^-1 X^T y.
/// False (use the QR route) when the Cholesky factorisation fails or the
/// estimate of cond(G_s) exceeds max_gram_condition.
bool gram_route_triangle(const std::vector<Piece>& pieces, Eigen::Index input_columns, Eigen::Index p,
                         double max_gram_condition, Eigen::MatrixXd& r11, Eigen::VectorXd& rhs, Eigen::VectorXd& column_norm) {
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(p + 1, p + 1);
  for (const Piece& piece : pieces) {
    g.triangularView<Eigen::Lower>() += piece.full_gram;
    // The reduced rows have zeros in the x0 columns: their Gram adds to the
    // B, D and y rows and columns only.
    const Eigen::Index ic = input_columns;
    g.topLeftCorner(ic, ic).triangularView<Eigen::Lower>() += piece.reduced_gram.topLeftCorner(ic, ic);
    g.row(p).head(ic) += piece.reduced_gram.row(ic).head(ic);
    g(p, p) += piece.reduced_gram(ic, ic);
  }
  column_norm = safe_column_norms(g.diagonal().head(p));
  const Eigen::MatrixXd gs = column_norm.cwiseInverse().asDiagonal() *
                             Eigen::MatrixXd(g.topLeftCorner(p, p).selfadjointView<Eigen::Lower>()) *
                             column_norm.cwiseInverse().asDiagonal();
  const Eigen::LLT<Eigen::MatrixXd> llt(gs);
  // LLT::rcond is the LAPACK-style 1-norm estimate of 1 / cond(G_s) (Hager-Higham).
  if (llt.info() != Eigen::Success || !(llt.rcond() * max_gram_condition >= 1.0)) return false;
  r11 = llt.matrixU();
  rhs = llt.matrixL().solve(g.row(p).head(p).transpose().cwiseQuotient(column_norm));
  return true;
}

}  // namespace

BdxLeastSquaresResult bdx_least_squares(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, const IoData& data,
                                        const BdxLeastSquaresOptions& options) {
  const Eigen::Index n = A.rows(), l = C.rows(), m = data.inputs();
  if (A.cols() != n || C.cols() != n) throw std::invalid_argument("bdx_least_squares: need A n x n and C l x n");
  if (l != data.outputs() || m < 1 || n < 1)
    throw std::invalid_argument("bdx_least_squares: need C with one row per output, at least one input and state");
  if (options.max_samples < 1) throw std::invalid_argument("bdx_least_squares: need max_samples >= 1");
  const Eigen::Index experiments = static_cast<Eigen::Index>(data.experiments.size());
  const Eigen::Index input_columns = n * m + l * m;
  const Eigen::Index p = input_columns + n * experiments;
  BdxLeastSquaresResult out;
  const Coordinates co = choose_coordinates(A, C, options.modal_condition_limit);
  out.modal_coordinates = co.modal;
  out.modal_condition = co.modal_condition;

  std::vector<Piece> pieces = cut_into_pieces(data, options.max_samples, out.samples_used);
  auto accumulate = [&](bool gram) {
    parallel_for(pieces.size(), [&](std::size_t k) {
      accumulate_piece(co, data.experiments[static_cast<std::size_t>(pieces[k].experiment)], experiments, gram, pieces[k]);
    });
    out.rows_without_initial_response = 0;
    for (const Piece& piece : pieces) out.rows_without_initial_response += piece.reduced_rows;
  };
  // The triangle and right-hand side of the column-equilibrated regression:
  // r11 = R S^-1 (S = the columns' norms) and rhs = Q^T y, from either route.
  Eigen::MatrixXd r11;
  Eigen::VectorXd rhs, column_norm;
  if (options.max_gram_condition > 0) {
    accumulate(true);
    out.normal_equations = gram_route_triangle(pieces, input_columns, p, options.max_gram_condition, r11, rhs, column_norm);
  }
  if (!out.normal_equations) {
    accumulate(false);
    qr_route_triangle(pieces, input_columns, p, r11, rhs, column_norm);
  }
  const Eigen::VectorXd d = r11.diagonal().cwiseAbs();
  out.condition = d.minCoeff() > 0 ? d.maxCoeff() / d.minCoeff() : std::numeric_limits<double>::infinity();
  // Rank-revealing solve of the small triangular system (guards against an unexcited direction).
  const Eigen::VectorXd theta = r11.completeOrthogonalDecomposition().solve(rhs).cwiseQuotient(column_norm);
  out.B = Eigen::Map<const Eigen::MatrixXd>(theta.data(), n, m);
  out.D = Eigen::Map<const Eigen::MatrixXd>(theta.data() + n * m, l, m);
  for (Eigen::Index e = 0; e < experiments; ++e) out.x0.push_back(theta.segment(input_columns + e * n, n));
  if (out.modal_coordinates) {
    out.B = co.T * out.B;
    for (Eigen::VectorXd& x0 : out.x0) x0 = co.T * x0;
  }
  return out;
}

}  // namespace sysid
