#pragma once
/// @file
/// Purpose: FIR identification of a MIMO path by the multi-step normalised LMS
/// algorithm, for streaming use (class MultiStepNlms) or on a whole record
/// (multistep_nlms()). The typical use is the actuator-by-actuator
/// identification of a vibration isolator: one input excited, all outputs
/// measured (SIMO), the FIR then turned into Markov parameters
/// (realization/markov_parameters.hpp) and realised by ERA (realization/era.hpp).
///
/// Model: y_i(k) = sum_{j=1}^{m} sum_{s=0}^{L-1} w_ij[s] u_j(k - s) + noise,
/// i = 1..l, with L taps per (output, input) path; w_ij[0] is the direct term, so
/// the taps are the Markov parameters h[0..L-1] of the path.
///
/// Method: with the regressor x(k) = [u(k); u(k-1); ...; u(k-L+1)] (all inputs,
/// lag-major, size m L) and the weight matrix W (m L x l, one column per output),
///
///   W(k+1) = W(k) + mu * sum_{i=0}^{K-1} gamma_{i+1} x(k-i) e_i(k)^T / (eps + ||x(k-i)||^2),
///   e_i(k) = y(k-i) - W(k)^T x(k-i),
///
/// with gamma_i >= 0 and sum_i gamma_i = 1. K = 1, gamma = {1} is ordinary NLMS
/// (Nagumo & Noda 1967). For K > 1 this is the multi-step ("data-reusing",
/// affine-projection-like) member of the NLMS family: the step is a convex
/// combination of the NLMS corrections for the K most recent regressors, i.e. a
/// relaxed averaged projection onto their K hyperplanes, where the affine
/// projection algorithm (Ozeki & Umeda 1984) would project onto their
/// intersection by solving a K x K Gram system.
///
/// Which error: e_i(k) is the error of the past sample k-i *re-evaluated with the
/// current weights W(k)* (its a-priori error with respect to this update), not
/// the a-priori error stored when sample k-i was first seen. Reason: with stored
/// errors every sample would receive its correction K times from an estimate
/// that is already out of date; the update then acts like NLMS with a delayed,
/// low-pass-filtered gradient, which converges no faster and is unstable on
/// coloured input already at mu = 1 (measured: 30 dB SNR, AR(1) input with pole
/// 0.9, 32 taps). With re-evaluated errors the matrix P(k) = sum gamma_i x_i x_i^T
/// / ||x_i||^2 is a convex combination of projections (0 <= P <= I), so the
/// noise-free error recursion W~(k+1) = (I - mu P(k)) W~(k) is non-expansive for
/// every 0 < mu <= 2, and its steady-state misadjustment is lower than NLMS's at
/// the same mu.
///
/// Trade-off (measured, coloured AR(1) input with pole 0.9, 30 dB SNR, 4 seeds):
/// at mu <= 1 the multi-step variant with K = 3 needs ~25 % more samples than
/// NLMS to reach -20 dB misalignment but ends 1-3 dB lower; at mu > 1 it is faster
/// (mu = 1.5: 480 vs 2100 samples), because NLMS's per-sample contraction of the
/// error along x(k) is |1 - mu|, the multi-step one's prod_i |1 - mu gamma_i|.
/// So the multi-step variant is the one to run with a large step size.
///
/// Implementation: the tapped delay line is a doubled ring buffer holding the
/// last L + K - 1 input samples twice, so every x(k-i), i < K, is a contiguous
/// window (an Eigen::Map, no copy); the K past outputs and normalisations are
/// kept in small ring buffers. update() does no heap allocation.
///
/// Preconditions (std::invalid_argument): taps >= 1; K = gamma.size() >= 1;
/// every gamma_i >= 0 and |sum gamma_i - 1| <= 1e-12; 0 < mu <= 2; eps >= 0;
/// curve_decimation >= 0; 0 <= error_forgetting < 1; true_fir entries l x m.
///
/// Numerical aspects: per sample O(K m L l) multiply-adds (K dot products and K
/// axpys per output) plus O(m L) for ||x(k)||^2, which is recomputed exactly
/// every sample (a recursive update would drift after a large transient, e.g. a
/// hammer tap, and mis-normalise the quiet samples that follow). A regressor with
/// eps + ||x||^2 = 0 (the empty delay line at start-up) contributes nothing.
/// eps is absolute, in squared input units: choose it well below L times the
/// input variance.
///
/// References:
/// - J. Nagumo, A. Noda, "A learning method for system identification", IEEE TAC
///   12(3):282-287, 1967 (NLMS).
/// - K. Ozeki, T. Umeda, "An adaptive filtering algorithm using an orthogonal
///   projection to an affine subspace and its properties", Electronics and
///   Communications in Japan 67-A(5):19-27, 1984 (affine projection).
/// - S. Haykin, "Adaptive Filter Theory", 4th ed., 2002, ch. 6 (NLMS) and sec. 6.8
///   (affine projection).
///
/// Example:
///   MultiStepNlmsOptions o; o.taps = 256; o.gamma = {0.5, 0.3, 0.2}; o.mu = 1.2;
///   MultiStepNlmsResult r = multistep_nlms(u, y, o);   // r.fir[s] is l x m
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

struct MultiStepNlmsOptions {
  int taps = 64;                      ///< L: FIR length per path, lag 0 (direct term) included
  std::vector<double> gamma = {1.0};  ///< K = gamma.size() step weights, gamma_i >= 0, sum = 1
  double mu = 0.5;                    ///< step size, 0 < mu <= 2 (see the file comment for the trade-off)
  double eps = 1e-8;                  ///< regularisation added to ||x||^2 (absolute, squared input units)
  /// One learning-curve point per this many samples (0 = no curve). Each point
  /// holds the mean of ||e_0(k)||^2 / l over the samples since the previous point.
  int curve_decimation = 100;
  /// Optional true FIR (entries l x m, any length; missing taps count as zero)
  /// to report the misalignment ||W - W_true||_F^2 / ||W_true||_F^2 in dB.
  std::vector<Eigen::MatrixXd> true_fir;
  /// Forgetting factor lambda of info().error_power:
  /// P(k) = lambda P(k-1) + (1 - lambda) ||e_0(k)||^2 / l (time constant 1 / (1 - lambda) samples).
  double error_forgetting = 0.99;
};

/// State of the streaming estimator (Eigen-decomposition style info()).
struct MultiStepNlmsInfo {
  Eigen::Index samples = 0;  ///< samples seen by update()
  double error_power = 0.0;  ///< exponentially smoothed ||e_0||^2 / l (see MultiStepNlmsOptions::error_forgetting)
};

struct LearningCurvePoint {
  Eigen::Index sample = 0;  ///< index of the last sample of the block (0-based)
  double error_power = 0.0;  ///< mean of ||e_0(k)||^2 / l over the block (a-priori errors)
  double misalignment_db = std::numeric_limits<double>::quiet_NaN();  ///< NaN without a true FIR
};

struct MultiStepNlmsResult {
  std::vector<Eigen::MatrixXd> fir;  ///< L entries, fir[s](i, j) = w_ij[s] (l x m): the Markov parameters
  Eigen::MatrixXd weights;           ///< m L x l, row s m + j, column i: w_ij[s] (the internal layout)
  std::vector<LearningCurvePoint> learning_curve;
  MultiStepNlmsInfo info;
  std::vector<std::string> warnings;
};

namespace detail {

inline void check_multistep_nlms_options(const MultiStepNlmsOptions& o, Eigen::Index inputs, Eigen::Index outputs) {
  if (inputs < 1) throw std::invalid_argument("multistep_nlms: need inputs >= 1");
  if (outputs < 1) throw std::invalid_argument("multistep_nlms: need outputs >= 1");
  if (o.taps < 1) throw std::invalid_argument("multistep_nlms: need taps >= 1");
  if (o.gamma.empty()) throw std::invalid_argument("multistep_nlms: need at least one step weight (gamma.size() >= 1)");
  double sum = 0.0;
  for (std::size_t i = 0; i < o.gamma.size(); ++i) {
    if (!(o.gamma[i] >= 0.0) || !std::isfinite(o.gamma[i]))
      throw std::invalid_argument("multistep_nlms: need gamma_" + std::to_string(i + 1) + " >= 0 (is " +
                                  std::to_string(o.gamma[i]) + ")");
    sum += o.gamma[i];
  }
  if (!(std::abs(sum - 1.0) <= 1e-12))
    throw std::invalid_argument("multistep_nlms: need sum of gamma_i == 1 (is " + std::to_string(sum) + ")");
  if (!(o.mu > 0.0 && o.mu <= 2.0)) throw std::invalid_argument("multistep_nlms: need 0 < mu <= 2 (is " + std::to_string(o.mu) + ")");
  if (!(o.eps >= 0.0) || !std::isfinite(o.eps)) throw std::invalid_argument("multistep_nlms: need eps >= 0");
  if (o.curve_decimation < 0) throw std::invalid_argument("multistep_nlms: need curve_decimation >= 0");
  if (!(o.error_forgetting >= 0.0 && o.error_forgetting < 1.0))
    throw std::invalid_argument("multistep_nlms: need 0 <= error_forgetting < 1");
  for (std::size_t s = 0; s < o.true_fir.size(); ++s)
    if (o.true_fir[s].rows() != outputs || o.true_fir[s].cols() != inputs)
      throw std::invalid_argument("multistep_nlms: true_fir[" + std::to_string(s) + "] must be " + std::to_string(outputs) +
                                  "x" + std::to_string(inputs));
}

}  // namespace detail

/// Purpose: streaming multi-step NLMS estimator (see the file comment).
/// Construct with the channel counts, feed one sample per update().
class MultiStepNlms {
 public:
  MultiStepNlms(Eigen::Index inputs, Eigen::Index outputs, MultiStepNlmsOptions options = {})
      : m_opt(std::move(options)), m_m(inputs), m_l(outputs) {
    detail::check_multistep_nlms_options(m_opt, inputs, outputs);
    m_taps = m_opt.taps;
    m_k = static_cast<Eigen::Index>(m_opt.gamma.size());
    m_window = m_taps + m_k - 1;
    m_line = Eigen::VectorXd::Zero(2 * m_window * m_m);
    m_w = Eigen::MatrixXd::Zero(m_taps * m_m, m_l);
    m_yhist = Eigen::MatrixXd::Zero(m_l, m_k);
    m_inv_norm = Eigen::VectorXd::Zero(m_k);
    m_err = Eigen::MatrixXd::Zero(m_l, m_k);
    m_coef = Eigen::VectorXd::Zero(m_l);
    m_e0 = Eigen::VectorXd::Zero(m_l);
    m_pos = 0;
    m_head = 0;
  }

  /// Purpose: processes sample k: u_row = u(k) (m values), y_row = y(k) (l values),
  /// rows or columns. Returns the a-priori error e_0(k) = y(k) - W(k)^T x(k)
  /// (a reference to internal storage, valid until the next call).
  /// Preconditions: sizes m and l (std::invalid_argument).
  template <class DU, class DY>
  const Eigen::VectorXd& update(const Eigen::MatrixBase<DU>& u_row, const Eigen::MatrixBase<DY>& y_row) {
    if (u_row.size() != m_m || y_row.size() != m_l)
      throw std::invalid_argument("MultiStepNlms::update: need " + std::to_string(m_m) + " inputs and " +
                                  std::to_string(m_l) + " outputs per sample");
    // Newest sample first: step the write position back and store u(k) twice,
    // at p and p + window, so x(k - i) = line[(p + i) m .. (p + i + L) m) never wraps.
    m_pos = (m_pos == 0 ? m_window : m_pos) - 1;
    double* line = m_line.data();
    for (Eigen::Index j = 0; j < m_m; ++j) {
      const double v = u_row.derived().coeff(j);
      line[m_pos * m_m + j] = v;
      line[(m_pos + m_window) * m_m + j] = v;
    }
    const Eigen::Index len = m_taps * m_m;
    // Ring slot of lag i: (m_head + i) mod K, newest at m_head.
    m_head = (m_head == 0 ? m_k : m_head) - 1;
    for (Eigen::Index i = 0; i < m_l; ++i) m_yhist(i, m_head) = y_row.derived().coeff(i);
    {
      const Eigen::Map<const Eigen::VectorXd> x0(line + m_pos * m_m, len);
      const double nrm = m_opt.eps + x0.squaredNorm();
      m_inv_norm[m_head] = nrm > 0.0 ? 1.0 / nrm : 0.0;
    }
    // Errors of the K most recent samples with the current weights.
    const Eigen::Index avail = std::min<Eigen::Index>(m_k, m_samples + 1);
    for (Eigen::Index i = 0; i < avail; ++i) {
      const Eigen::Map<const Eigen::VectorXd> xi(line + (m_pos + i) * m_m, len);
      const Eigen::Index slot = (m_head + i) % m_k;
      if (m_l == 1) {
        m_err(0, i) = m_yhist(0, slot) - xi.dot(m_w.col(0));
      } else {
        m_err.col(i) = m_yhist.col(slot);
        m_err.col(i).noalias() -= m_w.transpose() * xi;
      }
    }
    m_e0 = m_err.col(0);
    // W += mu sum_i gamma_i x_i e_i^T / (eps + ||x_i||^2).
    for (Eigen::Index i = 0; i < avail; ++i) {
      const double g = m_opt.mu * m_opt.gamma[static_cast<std::size_t>(i)] * m_inv_norm[(m_head + i) % m_k];
      if (g == 0.0) continue;
      const Eigen::Map<const Eigen::VectorXd> xi(line + (m_pos + i) * m_m, len);
      if (m_l == 1) {
        m_w.col(0) += (g * m_err(0, i)) * xi;
      } else {
        m_coef = g * m_err.col(i);
        m_w.noalias() += xi * m_coef.transpose();
      }
    }
    const double lam = m_opt.error_forgetting;
    const double e2 = m_e0.squaredNorm() / static_cast<double>(m_l);
    m_info.error_power = m_info.samples == 0 ? e2 : lam * m_info.error_power + (1.0 - lam) * e2;
    ++m_samples;
    m_info.samples = m_samples;
    return m_e0;
  }

  /// m L x l weights, row s m + j, column i = w_ij[s].
  const Eigen::MatrixXd& weights() const { return m_w; }

  /// The FIR as L matrices l x m: fir()[s](i, j) = w_ij[s] (allocates).
  std::vector<Eigen::MatrixXd> fir() const {
    std::vector<Eigen::MatrixXd> h(static_cast<std::size_t>(m_taps), Eigen::MatrixXd(m_l, m_m));
    for (Eigen::Index s = 0; s < m_taps; ++s)
      for (Eigen::Index j = 0; j < m_m; ++j) h[static_cast<std::size_t>(s)].col(j) = m_w.row(s * m_m + j).transpose();
    return h;
  }

  const MultiStepNlmsInfo& info() const { return m_info; }
  const MultiStepNlmsOptions& options() const { return m_opt; }
  Eigen::Index inputs() const { return m_m; }
  Eigen::Index outputs() const { return m_l; }

  /// Clears weights, delay line and history (options kept).
  void reset() {
    m_line.setZero();
    m_w.setZero();
    m_yhist.setZero();
    m_inv_norm.setZero();
    m_err.setZero();
    m_pos = m_head = 0;
    m_samples = 0;
    m_info = {};
  }

 private:
  MultiStepNlmsOptions m_opt;
  Eigen::Index m_m, m_l;
  Eigen::Index m_taps = 0, m_k = 0, m_window = 0;
  Eigen::VectorXd m_line;      // doubled ring buffer, 2 window m values, lag-major within a sample
  Eigen::MatrixXd m_w;         // m L x l
  Eigen::MatrixXd m_yhist;     // l x K ring of past outputs
  Eigen::VectorXd m_inv_norm;  // K ring of 1 / (eps + ||x||^2)
  Eigen::MatrixXd m_err;       // l x K errors of this step, column i = lag i
  Eigen::VectorXd m_coef;      // l, scratch
  Eigen::VectorXd m_e0;        // l, a-priori error returned by update()
  Eigen::Index m_pos = 0, m_head = 0;
  Eigen::Index m_samples = 0;
  MultiStepNlmsInfo m_info;
};

/// Purpose: runs MultiStepNlms over a whole record (u: N x m, y: N x l, samples in
/// rows) from zero weights and an empty delay line (u(k < 0) = 0), and records
/// the learning curve.
/// Preconditions: u.rows() == y.rows() >= 1, options as in the file comment
/// (std::invalid_argument).
/// Warnings: fewer than 10 L samples; an input that is identically zero (its
/// paths stay zero); FIR not decayed (largest ||fir[s]|| over the last tenth of
/// the taps > 5 % of the largest overall, L >= 8); error power of the last curve block not at least 3 dB below
/// the first one (not converged, or no signal to learn).
template <class DU, class DY>
MultiStepNlmsResult multistep_nlms(const Eigen::MatrixBase<DU>& u, const Eigen::MatrixBase<DY>& y,
                                   const MultiStepNlmsOptions& options = {}) {
  if (u.rows() != y.rows())
    throw std::invalid_argument("multistep_nlms: need u.rows() == y.rows() (" + std::to_string(u.rows()) +
                                " != " + std::to_string(y.rows()) + ")");
  if (u.rows() < 1) throw std::invalid_argument("multistep_nlms: need at least one sample");
  // Fewer samples than taps leave taps the data never reached: an FIR that only
  // looks identified.
  if (u.rows() < options.taps)
    throw std::invalid_argument("multistep_nlms: " + std::to_string(u.rows()) + " samples cannot determine " +
                                std::to_string(options.taps) + " taps: need at least as many samples as taps (about " +
                                "10 per tap to converge)");
  const Eigen::Ref<const Eigen::MatrixXd> ur(u.derived());
  const Eigen::Ref<const Eigen::MatrixXd> yr(y.derived());
  if (!ur.allFinite() || !yr.allFinite()) throw std::invalid_argument("multistep_nlms: u and y must be finite");
  MultiStepNlms est(ur.cols(), yr.cols(), options);
  const Eigen::Index N = ur.rows(), m = ur.cols(), l = yr.cols(), L = options.taps;

  // True weights in the internal layout, zero-padded to L, plus the energy of
  // any true taps beyond L (which the model cannot represent).
  const bool have_true = !options.true_fir.empty();
  Eigen::MatrixXd w_true = Eigen::MatrixXd::Zero(L * m, l);
  double true_energy = 0.0, tail_energy = 0.0;
  for (std::size_t s = 0; s < options.true_fir.size(); ++s) {
    const Eigen::MatrixXd& hs = options.true_fir[s];
    true_energy += hs.squaredNorm();
    if (static_cast<Eigen::Index>(s) < L)
      for (Eigen::Index j = 0; j < m; ++j) w_true.row(static_cast<Eigen::Index>(s) * m + j) = hs.col(j).transpose();
    else
      tail_energy += hs.squaredNorm();
  }
  auto misalignment_db = [&]() {
    if (!have_true || true_energy <= 0.0) return std::numeric_limits<double>::quiet_NaN();
    return 10.0 * std::log10(((est.weights() - w_true).squaredNorm() + tail_energy) / true_energy);
  };

  MultiStepNlmsResult res;
  const int dec = options.curve_decimation;
  if (dec > 0) res.learning_curve.reserve(static_cast<std::size_t>(N / dec + 1));
  double block_sum = 0.0;
  Eigen::Index block_count = 0;
  for (Eigen::Index k = 0; k < N; ++k) {
    const Eigen::VectorXd& e = est.update(ur.row(k), yr.row(k));
    block_sum += e.squaredNorm() / static_cast<double>(l);
    ++block_count;
    if (dec > 0 && (block_count == dec || k + 1 == N)) {
      res.learning_curve.push_back({k, block_sum / static_cast<double>(block_count), misalignment_db()});
      block_sum = 0.0;
      block_count = 0;
    }
  }
  res.weights = est.weights();
  res.fir = est.fir();
  res.info = est.info();

  if (N < 10 * static_cast<Eigen::Index>(L))
    res.warnings.push_back("only " + std::to_string(N) + " samples for " + std::to_string(L) +
                           " taps (< 10 per tap): the FIR may not have converged");
  for (Eigen::Index j = 0; j < m; ++j)
    if (ur.col(j).cwiseAbs().maxCoeff() == 0.0)
      res.warnings.push_back("input " + std::to_string(j + 1) + " is identically zero: its paths stay zero");
  // Tail: the largest tap matrix among the last tenth (a single last tap may sit
  // at a zero crossing of a ringing mode).
  double hmax = 0.0, tail = 0.0;
  for (Eigen::Index s = 0; s < L; ++s) {
    const double nrm = res.fir[static_cast<std::size_t>(s)].norm();
    hmax = std::max(hmax, nrm);
    if (s >= L - std::max<Eigen::Index>(1, L / 10)) tail = std::max(tail, nrm);
  }
  if (L >= 8 && hmax > 0.0 && tail > 0.05 * hmax)
    res.warnings.push_back("the FIR has not decayed within " + std::to_string(L) + " taps (tail/peak = " +
                           std::to_string(tail / hmax) +
                           "): the unmodelled tail acts as noise (white input) or bias (coloured input); increase taps");
  if (res.learning_curve.size() >= 4) {
    const double first = res.learning_curve.front().error_power, last = res.learning_curve.back().error_power;
    if (!(last < 0.5 * first))
      res.warnings.push_back("error power fell by less than 3 dB over the record (first block " + std::to_string(first) +
                             ", last block " + std::to_string(last) + "): not converged or nothing to learn");
  }
  return res;
}

/// Purpose: the FIR of one recorded experiment as the command line (`sysid lms`)
/// and the Python package (`sysid.lms`) identify it: channel means removed, and
/// options.eps taken relative to the input power, 1e-8 L E[|u|^2], so the
/// regularisation stays negligible whatever the units (inputs in nanometres or in
/// kilonewtons); the library's eps is absolute (squared input units).
inline MultiStepNlmsResult multistep_nlms_on_record(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                                                    MultiStepNlmsOptions options) {
  const Eigen::RowVectorXd u_mean = u.colwise().mean(), y_mean = y.colwise().mean();
  const double u_power = (u.rowwise() - u_mean).squaredNorm() / static_cast<double>(std::max<Eigen::Index>(u.rows(), 1));
  if (u_power > 0.0) options.eps = 1e-8 * static_cast<double>(options.taps) * u_power;
  return multistep_nlms(u.rowwise() - u_mean, y.rowwise() - y_mean, options);
}

}  // namespace sysid
