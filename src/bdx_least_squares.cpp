// Implementation of subspace/bdx_least_squares.hpp (method and references there).
#include <sysid/subspace/bdx_least_squares.hpp>

#include <sysid/core/detail/real_modal_form.hpp>
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
/// rows with x0 regressors (wider QR), the second first runs the recursion alone
/// up to its start (28 ns a sample against ~90 ns for recursion, rows and QR);
/// on the Par2 log (order 10, SISO, modal coordinates, 40 000 samples) 0.54 gave
/// 2.1 ms against 1.9 ms run one after the other; 0.52 should about balance them
/// (a split that is off only costs time, never accuracy).
constexpr double kFirstPieceShare = 0.52;

/// The regressors' recursion, one sample at a time, on the transposed state:
/// columns q l .. q l + l - 1 of `state` hold Psi_q^T, the last l columns
/// Lambda^T, and state <- A^T state + [u_q C^T ..., 0].
class Recursion {
 public:
  /// `blocks` non-empty: A^T is block diagonal with these blocks (modal
  /// coordinates), `At` unused; otherwise the dense `At`.
  Recursion(const Eigen::MatrixXd& At, const std::vector<detail::RealModalBlock>& blocks, const Eigen::MatrixXd& Ct,
            Eigen::Index m)
      : m_At(At), m_blocks(blocks), m_Ct(Ct), m_state(Ct.rows(), (m + 1) * Ct.cols()), m_next(m_state.rows(), m_state.cols()) {
    m_state.leftCols(m * Ct.cols()).setZero();
    m_state.rightCols(Ct.cols()) = Ct;
  }

  const Eigen::MatrixXd& state() const { return m_state; }

  /// Whether the current sample's x0 regressors are negligible (and updates their running peak).
  bool initial_response_negligible() {
    const Eigen::Index l = m_Ct.cols(), n = m_state.rows();
    const double* lambda = m_state.data() + (m_state.cols() - l) * n;  // the last l columns, contiguous
    double response = 0;
    for (Eigen::Index k = 0; k < n * l; ++k) response = std::max(response, std::abs(lambda[k]));
    m_initial_response_peak = std::max(m_initial_response_peak, response);
    return response <= kNegligibleInitialResponse * m_initial_response_peak;
  }

  template <class Row>
  void advance(const Row& u) {
    if (m_blocks.empty()) {
      // lazyProduct keeps this small product inline: the general GEMM dispatch
      // costs more than the product itself at these sizes.
      m_next.noalias() = m_At.lazyProduct(m_state);
    } else {
      // A_m^T blocks: [lambda] or [[Re, -Im], [Im, Re]] (the transpose of
      // real_modal_block), applied down each column with scalar code: Eigen's
      // row expressions of a column-major matrix cost more than the arithmetic.
      for (Eigen::Index j = 0; j < m_state.cols(); ++j) {
        const double* s = m_state.col(j).data();
        double* x = m_next.col(j).data();
        for (const detail::RealModalBlock& b : m_blocks) {
          const Eigen::Index k = b.start;
          const double re = b.lambda.real();
          if (b.size == 1) {
            x[k] = re * s[k];
          } else {
            const double im = b.lambda.imag();
            x[k] = re * s[k] - im * s[k + 1];
            x[k + 1] = im * s[k] + re * s[k + 1];
          }
        }
      }
    }
    const Eigen::Index n = m_state.rows(), l = m_Ct.cols();
    const double* ct = m_Ct.data();
    for (Eigen::Index q = 0; q < u.size(); ++q) {
      const double uq = u(q);
      double* psi = m_next.data() + q * l * n;  // Psi_q^T: columns q l .. q l + l - 1, contiguous
      for (Eigen::Index k = 0; k < n * l; ++k) psi[k] += uq * ct[k];
    }
    m_state.swap(m_next);
  }

 private:
  const Eigen::MatrixXd& m_At;
  const std::vector<detail::RealModalBlock>& m_blocks;
  const Eigen::MatrixXd& m_Ct;
  Eigen::MatrixXd m_state, m_next;
  double m_initial_response_peak = 0;
};

/// The recursion's system: A^T (dense) or the modal blocks, and C^T, in the
/// coordinates the regression runs in; T maps those back (empty: identity).
struct Coordinates {
  Eigen::MatrixXd At, Ct, T;
  std::vector<detail::RealModalBlock> blocks;
  double modal_condition = std::numeric_limits<double>::infinity();
};

Coordinates choose_coordinates(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, double modal_condition_limit) {
  Coordinates c;
  detail::RealModalForm form;
  if (detail::real_modal_form(A, form) == detail::RealModalStatus::ok) {
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(form.T).singularValues();
    if (sv(sv.size() - 1) > 0) c.modal_condition = sv(0) / sv(sv.size() - 1);
  }
  if (c.modal_condition <= modal_condition_limit) {
    c.T = form.T;
    c.blocks = form.blocks;
    c.Ct = (C * form.T).transpose();
  } else {
    c.At = A.transpose();
    c.Ct = C.transpose();
  }
  return c;
}

/// The rows of samples [begin, end) of one experiment, in their own QRs.
struct Piece {
  Eigen::Index experiment = 0, begin = 0, end = 0;
  std::optional<StreamingQR> full, reduced;  ///< rows with and without x0 regressors
  Eigen::Index full_rows = 0, reduced_rows = 0;
};

void accumulate_piece(const Coordinates& co, const Experiment& ex, Eigen::Index experiments, Piece& piece) {
  const Eigen::Index n = co.Ct.rows(), l = co.Ct.cols(), m = ex.u.cols();
  const Eigen::Index input_columns = n * m + l * m;  // B then D: the columns every row has
  const Eigen::Index p = input_columns + n * experiments;
  piece.full.emplace(p + 1);
  piece.reduced.emplace(input_columns + 1);
  Recursion rec(co.At, co.blocks, co.Ct, m);
  for (Eigen::Index t = 0; t < piece.begin; ++t) {
    rec.initial_response_negligible();  // keeps the running peak a single pass would have
    rec.advance(ex.u.row(t));
  }
  // Rows of `block` samples are formed together and handed to the QRs at once,
  // into buffers reused for every block (no allocation per sample).
  const Eigen::Index block = 256;
  Eigen::MatrixXd rows(block * l, p + 1), reduced_rows(block * l, input_columns + 1);
  for (Eigen::Index start = piece.begin; start < piece.end; start += block) {
    const Eigen::Index count = std::min(block, piece.end - start);
    Eigen::Index full = 0, reduced = 0;  // rows filled in each buffer
    rows.topRows(count * l).setZero();
    reduced_rows.topRows(count * l).setZero();
    for (Eigen::Index k = 0; k < count; ++k) {
      const Eigen::Index t = start + k;
      const bool negligible = rec.initial_response_negligible();
      auto r_t = negligible ? reduced_rows.middleRows(reduced * l, l) : rows.middleRows(full * l, l);
      (negligible ? reduced : full) += 1;
      const Eigen::MatrixXd& state = rec.state();
      for (Eigen::Index q = 0; q < m; ++q) r_t.middleCols(q * n, n) = state.middleCols(q * l, l).transpose();
      for (Eigen::Index q = 0; q < m; ++q)
        for (Eigen::Index r = 0; r < l; ++r) r_t(r, n * m + q * l + r) = ex.u(t, q);
      if (!negligible) r_t.middleCols(input_columns + piece.experiment * n, n) = state.rightCols(l).transpose();
      r_t.col(r_t.cols() - 1) = ex.y.row(t).transpose();
      rec.advance(ex.u.row(t));
    }
    if (full > 0) piece.full->add_rows(rows.topRows(full * l));
    if (reduced > 0) piece.reduced->add_rows(reduced_rows.topRows(reduced * l));
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
    pieces.push_back({experiment, 0, cut, {}, {}, 0, 0});
    if (cut < samples) pieces.push_back({experiment, cut, samples, {}, {}, 0, 0});
  }
  return pieces;
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
  out.modal_coordinates = !co.blocks.empty();
  out.modal_condition = co.modal_condition;

  std::vector<Piece> pieces = cut_into_pieces(data, options.max_samples, out.samples_used);
  parallel_for(pieces.size(), [&](std::size_t k) {
    accumulate_piece(co, data.experiments[static_cast<std::size_t>(pieces[k].experiment)], experiments, pieces[k]);
  });
  // Merge in the pieces' order: the full triangles, then the reduced ones with
  // zeros in every x0 column.
  StreamingQR qr(p + 1), reduced_qr(input_columns + 1);
  for (Piece& piece : pieces) {
    if (piece.full_rows > 0) qr.add_rows(piece.full->r());
    if (piece.reduced_rows > 0) reduced_qr.add_rows(piece.reduced->r());
    out.rows_without_initial_response += piece.reduced_rows;
  }
  if (out.rows_without_initial_response > 0) {
    const Eigen::MatrixXd r_reduced = reduced_qr.r();
    Eigen::MatrixXd merged = Eigen::MatrixXd::Zero(r_reduced.rows(), p + 1);
    merged.leftCols(input_columns) = r_reduced.leftCols(input_columns);
    merged.col(p) = r_reduced.col(input_columns);
    qr.add_rows(merged);
  }
  const Eigen::MatrixXd r = qr.r();
  // Column equilibration before the rank decision: the regressors' scales can
  // differ by many decades (C A^t and the B regressors grow like rho(A)^t when
  // A is unstable: 1e21 over 600 samples at rho = 1.083), and a rank threshold
  // relative to the largest pivot then discards every other column, B = D = 0.
  // The column norms of R are those of the regression (Q is orthogonal), and
  // R S is the R factor of M S, so scaling after the QR is scaling the data.
  Eigen::VectorXd column_norm = r.topLeftCorner(p, p).colwise().norm().transpose();
  for (double& c : column_norm)
    if (!(c > 0.0)) c = 1.0;  // an all-zero regressor (input constant zero) stays zero
  const Eigen::MatrixXd r11 = r.topLeftCorner(p, p) * column_norm.cwiseInverse().asDiagonal();
  const Eigen::VectorXd d = r11.diagonal().cwiseAbs();
  out.condition = d.minCoeff() > 0 ? d.maxCoeff() / d.minCoeff() : std::numeric_limits<double>::infinity();
  // Rank-revealing solve of the small triangular system (guards against an unexcited direction).
  const Eigen::VectorXd theta =
      r11.completeOrthogonalDecomposition().solve(r.topRightCorner(p, 1)).cwiseQuotient(column_norm);
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
