#pragma once
/// @file
/// Purpose: non-parametric frequency-response (FRF) estimates from input/output
/// records: H1 and H2, ordinary and multiple coherence, and confidence bounds on
/// magnitude and phase; the MIMO FRF matrix from simultaneous excitation of all
/// inputs or from one-input-at-a-time experiments.
///
/// Method (Bendat & Piersol, Random Data, 4th ed., 2010, ch. 6, 7 and 9):
/// one-sided Welch spectra (spectral/welch.hpp) G_uu (m x m), G_uy (m x l) and G_yy,
/// with G_ab = E[conj(A) B^T] (B&P's convention, conjugate on the first index),
/// averaged over all segments of all experiments. Per frequency:
/// - H1 (least squares with noise on the outputs only; B&P eq. 6.37 / 7.x):
///   H^T = G_uu^{-1} G_uy, i.e. H = G_yu G_uu^{-1}; SISO H1 = G_uy / G_uu.
///   G_uu is Hermitian positive semi-definite; it is inverted through its
///   eigen-decomposition, whose eigenvalue ratio is the reported 2-norm condition
///   number. Frequencies with condition > max_condition are flagged (the inputs are
///   nearly linearly dependent there: correlated drives, an input without power, or
///   feedback), a warning says how many; the estimate there is kept but unreliable,
///   and NaN where G_uu is numerically singular.
/// - H2 (noise on the inputs only): SISO H2 = G_yy / G_yu with G_yu = conj(G_uy);
///   with m > 1 inputs it needs l = m outputs: H^T = G_yu^{-1} G_yy (G_yu = G_uy^H).
/// - ordinary coherence gamma^2_ij = |G_{u_j y_i}|^2 / (G_{u_j u_j} G_{y_i y_i}) (B&P eq. 6.40);
/// - multiple coherence of output i (B&P sec. 7.3.3):
///   gamma^2_{y_i:u} = g^H G_uu^{-1} g / G_{y_i y_i}, g = G_uy(:, i);
/// - confidence bounds: the first-order normalised random error of |H|
///   (B&P sec. 9.2.4, Table 9.6): eps = sqrt(1 - gamma^2) / (|gamma| sqrt(2 n_d)),
///   with n_d the number of independent averages. Here n_d = nu / 2, nu Welch's
///   equivalent degrees of freedom (overlapped segments are not independent, so
///   n_d < K). For m inputs the same first-order analysis gives
///   Var(H_ij) = G_vv,i (G_uu^{-1})_jj / n_d', G_vv,i = (1 - gamma^2_{y_i:u}) G_{y_i y_i}
///   the residual (noise) spectrum and n_d' = n_d - (m - 1) (averages used up by the
///   other inputs' regression, as in B&P sec. 9.3), and eps_ij = sqrt(Var/2) / |H_ij|;
///   for m = 1 this is exactly the formula above. The same eps is the standard
///   deviation of the phase in radians (B&P Table 9.6). With z the normal quantile of
///   (1 + confidence)/2:
///     |H| in [|H_hat| max(0, 1 - z eps), |H_hat| (1 + z eps)],  phase in phase_hat +- min(pi, z eps).
///   Validity: first-order (Gaussian) approximation, good for eps <= 0.2 and
///   n_d >= ~20 (B&P sec. 9.1.3); bias errors (leakage, resolution: the window's
///   bandwidth must be narrow against resonance bandwidths; B&P sec. 9.2.2) are not
///   included; at low coherence (eps > 0.2) the bounds are only indicative and a
///   warning says at how many frequencies that happens.
/// - one input at a time (B&P sec. 7.4, "multiple-input/multiple-output" with
///   separate tests): each experiment drives one input; column j of H is the SISO H1
///   (or H2) of all outputs against input j over the experiments that drive it.
///   When the other inputs are not quiet in those experiments the columns are
///   biased; then frf(), which pools G_uu over all experiments and solves with the
///   full matrix, is the right estimate (it works for any mix of experiments whose
///   summed G_uu is well conditioned).
#include <sysid/core/io_data.hpp>
#include <sysid/core/median.hpp>
#include <sysid/core/distributions.hpp>
#include <sysid/spectral/welch.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

enum class FrfEstimator { h1, h2 };

struct FrfOptions {
  WelchOptions welch{};                     ///< segments, window, overlap, detrend (scaling is always density)
  FrfEstimator estimator = FrfEstimator::h1;  ///< H1 (output noise) or H2 (input noise)
  double confidence = 0.95;                 ///< level of the magnitude and phase bounds, 0 < confidence < 1
  /// G_uu condition number (ratio of its extreme eigenvalues, a power ratio) above
  /// which a frequency is flagged ill-conditioned: 1e6 is an amplitude ratio of 1000
  /// between the best and worst excited input directions. > 1.
  double max_condition = 1e6;
  /// frf_one_at_a_time only: the input each experiment drives (one entry per
  /// experiment, 0-based). Empty: the input with the largest variance.
  std::vector<Eigen::Index> excited_input;
  /// frf_one_at_a_time only: warn when a non-driven input's RMS exceeds this
  /// fraction of the driven input's RMS in the same experiment. >= 0.
  double quiet_input_ratio = 0.05;
};

struct FrfResult {
  Eigen::VectorXd freq_hz;                  ///< nfft/2 + 1 frequencies k fs / nfft
  std::vector<Eigen::MatrixXcd> H;          ///< one l x m matrix per frequency (NaN where G_uu is singular)
  std::vector<Eigen::MatrixXd> coherence;   ///< ordinary coherence gamma^2, l x m per frequency
  Eigen::MatrixXd multiple_coherence;       ///< frequencies x l; 0 x 0 for frf_one_at_a_time
  std::vector<Eigen::MatrixXd> random_error;  ///< normalised random error eps of |H|, l x m per frequency
  std::vector<Eigen::MatrixXd> magnitude_lower;      ///< lower bound on |H|, l x m per frequency
  std::vector<Eigen::MatrixXd> magnitude_upper;      ///< upper bound on |H|
  std::vector<Eigen::MatrixXd> phase_halfwidth_rad;  ///< phase(H) within phase(H_hat) +- this
  Eigen::MatrixXd input_psd;        ///< frequencies x m, G_{u_j u_j} (units^2/Hz)
  Eigen::MatrixXd output_psd;       ///< frequencies x l, G_{y_i y_i}
  Eigen::VectorXd input_condition;  ///< frequencies; condition of G_uu (1 for one input; for one-at-a-time: 1)
  std::vector<bool> ill_conditioned;  ///< per frequency: input_condition > max_condition or G_uu singular
  std::vector<Eigen::Index> segments;  ///< per input column: segments averaged
  Eigen::VectorXd dof;                 ///< per input column: Welch equivalent degrees of freedom nu
  Eigen::Index nfft = 0;
  FrfEstimator estimator = FrfEstimator::h1;
  double confidence = 0.95;
  std::vector<std::string> warnings;

  Eigen::Index outputs() const { return H.empty() ? 0 : H.front().rows(); }
  Eigen::Index inputs() const { return H.empty() ? 0 : H.front().cols(); }

  /// Two or three lines: estimator, size, nfft, averages, median coherence, warnings count.
  std::string brief_report() const {
    std::ostringstream s;
    s << (estimator == FrfEstimator::h1 ? "H1" : "H2") << " FRF, " << outputs() << " output(s) x " << inputs()
      << " input(s), nfft " << nfft << ", " << freq_hz.size() << " frequencies";
    if (!segments.empty()) s << ", " << segments.front() << " segments (nu = " << dof(0) << ")";
    std::vector<double> c;
    for (const auto& m : coherence)
      for (Eigen::Index k = 0; k < m.size(); ++k)
        if (std::isfinite(m(k))) c.push_back(m(k));
    if (!c.empty()) s << "\nmedian coherence " << median(std::move(c));
    for (const auto& w : warnings) s << "\nwarning: " << w;
    return s.str();
  }
};

namespace detail {

/// Summed one-sided density spectra for an FRF estimate.
struct FrfSpectra {
  Eigen::VectorXd freq_hz;
  std::vector<Eigen::MatrixXcd> Guu;  ///< m x m Hermitian
  std::vector<Eigen::MatrixXcd> Guy;  ///< m x l
  std::vector<Eigen::MatrixXcd> Gyy;  ///< l x l Hermitian if full, else only the diagonal is set
  Eigen::Index segments = 0;
  double dof = 0.0;
  Eigen::Index nfft = 0;
};

/// Welch sums over the listed experiments, inputs either all columns (input < 0)
/// or the single column `input`. One pass over every experiment: each channel's
/// segment is transformed once and all pairs formed from the spectra.
inline FrfSpectra frf_spectra(const IoData& data, const std::vector<std::size_t>& experiments, Eigen::Index input,
                              bool full_yy, const SegmentPlan& plan, double fs_hz) {
  const Eigen::Index m = input < 0 ? data.inputs() : 1, l = data.outputs();
  std::vector<std::pair<Eigen::Index, Eigen::Index>> pairs;
  for (Eigen::Index j = 0; j < m; ++j)
    for (Eigen::Index i = 0; i <= j; ++i) pairs.emplace_back(i, j);
  for (Eigen::Index j = 0; j < l; ++j)
    for (Eigen::Index i = 0; i < m; ++i) pairs.emplace_back(i, m + j);
  for (Eigen::Index j = 0; j < l; ++j)
    for (Eigen::Index i = full_yy ? 0 : j; i <= j; ++i) pairs.emplace_back(m + i, m + j);
  PairSums sums(std::move(pairs), plan.bins);
  SegmentTransform transform(plan);
  Eigen::MatrixXcd spectra(plan.bins, m + l);
  FrfSpectra out;
  out.nfft = plan.nfft;
  out.freq_hz = bin_frequencies(plan, fs_hz);
  for (const std::size_t e : experiments) {
    const Experiment& ex = data.experiments[e];
    const Eigen::Index k = input < 0 ? for_each_segment(ex.u, ex.y, plan, transform, spectra, sums)
                                     : for_each_segment(ex.u.col(input), ex.y, plan, transform, spectra, sums);
    out.segments += k;
    out.dof += welch_dof(plan, k);
  }
  const Eigen::VectorXd scale = one_sided_scale(plan, fs_hz, SpectralScaling::density, out.segments);
  const auto nb = static_cast<std::size_t>(plan.bins);
  out.Guu.assign(nb, Eigen::MatrixXcd::Zero(m, m));
  out.Guy.assign(nb, Eigen::MatrixXcd::Zero(m, l));
  out.Gyy.assign(nb, Eigen::MatrixXcd::Zero(l, l));
  for (Eigen::Index b = 0; b < plan.bins; ++b) {
    const auto bi = static_cast<std::size_t>(b);
    for (std::size_t k = 0; k < sums.pairs.size(); ++k) {
      const auto [i, j] = sums.pairs[k];
      const std::complex<double> v = sums.sums(b, static_cast<Eigen::Index>(k)) * scale(b);
      if (j < m) {
        out.Guu[bi](i, j) = v;
        out.Guu[bi](j, i) = std::conj(v);
      } else if (i < m) {
        out.Guy[bi](i, j - m) = v;
      } else {
        out.Gyy[bi](i - m, j - m) = v;
        out.Gyy[bi](j - m, i - m) = std::conj(v);
      }
    }
  }
  return out;
}

/// Per-frequency estimator, coherences and bounds from summed spectra (file comment).
inline FrfResult solve_frf(const FrfSpectra& g, const FrfOptions& o, bool multiple_coherence) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto nb = g.Guu.size();
  const Eigen::Index m = g.Guu.front().rows(), l = g.Guy.front().cols();
  FrfResult r;
  r.freq_hz = g.freq_hz;
  r.nfft = g.nfft;
  r.estimator = o.estimator;
  r.confidence = o.confidence;
  r.segments.assign(static_cast<std::size_t>(m), g.segments);
  r.dof = Eigen::VectorXd::Constant(m, g.dof);
  r.H.resize(nb);
  r.coherence.resize(nb);
  r.random_error.resize(nb);
  r.magnitude_lower.resize(nb);
  r.magnitude_upper.resize(nb);
  r.phase_halfwidth_rad.resize(nb);
  r.multiple_coherence = Eigen::MatrixXd(static_cast<Eigen::Index>(nb), l);
  r.input_psd.resize(static_cast<Eigen::Index>(nb), m);
  r.output_psd.resize(static_cast<Eigen::Index>(nb), l);
  r.input_condition.resize(static_cast<Eigen::Index>(nb));
  r.ill_conditioned.assign(nb, false);
  const double z = normal_quantile(0.5 * (1.0 + o.confidence));
  const double nd = 0.5 * g.dof - static_cast<double>(m - 1);  // independent averages left for the noise
  Eigen::Index n_ill = 0, n_singular = 0, n_loose = 0, n_bounded = 0;
  double first_ill = nan;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig(m);
  for (std::size_t b = 0; b < nb; ++b) {
    const auto bi = static_cast<Eigen::Index>(b);
    const Eigen::MatrixXcd& Guu = g.Guu[b];
    const Eigen::MatrixXcd& Guy = g.Guy[b];
    const Eigen::VectorXd gu = Guu.diagonal().real();
    const Eigen::VectorXd gy = g.Gyy[b].diagonal().real();
    r.input_psd.row(bi) = gu.transpose();
    r.output_psd.row(bi) = gy.transpose();
    eig.compute(Guu);
    const Eigen::VectorXd lam = eig.eigenvalues();  // ascending
    const double lmax = lam(m - 1), lmin = lam(0);
    const bool singular = !(lmax > 0.0) || !(lmin > lmax * 1e3 * std::numeric_limits<double>::epsilon());
    r.input_condition(bi) = singular ? std::numeric_limits<double>::infinity() : lmax / lmin;
    if (singular || r.input_condition(bi) > o.max_condition) {
      r.ill_conditioned[b] = true;
      if (n_ill++ == 0) first_ill = g.freq_hz(bi);
    }
    Eigen::MatrixXcd H(l, m);
    Eigen::MatrixXd coh(l, m), eps(l, m), lo(l, m), hi(l, m), ph(l, m);
    Eigen::MatrixXcd Guu_inv(m, m);
    if (singular) {
      ++n_singular;
      H.setConstant(std::complex<double>(nan, nan));
      Guu_inv.setConstant(nan);
      r.multiple_coherence.row(bi).setConstant(nan);
    } else {
      Guu_inv = eig.eigenvectors() * lam.cwiseInverse().asDiagonal() * eig.eigenvectors().adjoint();
      const Eigen::MatrixXcd Ht = Guu_inv * Guy;  // H1^T = G_uu^{-1} G_uy
      for (Eigen::Index i = 0; i < l; ++i) {
        const double explained = std::real(Guy.col(i).dot(Ht.col(i)));  // g^H G_uu^{-1} g
        r.multiple_coherence(bi, i) = gy(i) > 0.0 ? explained / gy(i) : nan;
      }
      if (o.estimator == FrfEstimator::h1) {
        H = Ht.transpose();
      } else if (m == 1) {
        for (Eigen::Index i = 0; i < l; ++i) H(i, 0) = gy(i) / std::conj(Guy(0, i));
      } else {
        H = Guy.adjoint().partialPivLu().solve(g.Gyy[b]).transpose();  // H2^T = G_yu^{-1} G_yy
      }
    }
    for (Eigen::Index i = 0; i < l; ++i) {
      const double mc = r.multiple_coherence(bi, i);
      const double gvv = std::max(0.0, (1.0 - mc)) * gy(i);  // residual (noise) spectrum
      for (Eigen::Index j = 0; j < m; ++j) {
        const double denom = gu(j) * gy(i);
        coh(i, j) = denom > 0.0 ? std::norm(Guy(j, i)) / denom : nan;
        const double var = nd > 0.0 ? gvv * std::real(Guu_inv(j, j)) / nd : nan;  // Var(H_ij), complex
        const double mag = std::abs(H(i, j));
        eps(i, j) = std::sqrt(0.5 * var) / mag;
        if (std::isfinite(eps(i, j))) {
          ++n_bounded;
          if (eps(i, j) > 0.2) ++n_loose;
          lo(i, j) = mag * std::max(0.0, 1.0 - z * eps(i, j));
          hi(i, j) = mag * (1.0 + z * eps(i, j));
          ph(i, j) = std::min(std::numbers::pi, z * eps(i, j));
        } else {
          lo(i, j) = 0.0;
          hi(i, j) = std::numeric_limits<double>::infinity();
          ph(i, j) = std::numbers::pi;
        }
      }
    }
    if (!multiple_coherence) r.multiple_coherence.row(bi).setConstant(nan);
    r.H[b] = std::move(H);
    r.coherence[b] = std::move(coh);
    r.random_error[b] = std::move(eps);
    r.magnitude_lower[b] = std::move(lo);
    r.magnitude_upper[b] = std::move(hi);
    r.phase_halfwidth_rad[b] = std::move(ph);
  }
  if (n_ill > 0) {
    std::ostringstream s;
    s << "input cross-spectral matrix ill-conditioned (condition > " << o.max_condition << ") at " << n_ill << " of " << nb
      << " frequencies (first at " << first_ill << " Hz";
    if (n_singular > 0) s << "; singular at " << n_singular << ", FRF set to NaN there";
    s << "): inputs nearly dependent or not excited there";
    r.warnings.push_back(s.str());
  }
  if (!(nd > 0.0)) r.warnings.push_back("too few averages for confidence bounds (n_d - (m - 1) <= 0): bounds are infinite");
  else if (n_loose > 0 && n_bounded > 0) {
    std::ostringstream s;
    s << "normalised random error > 0.2 at " << n_loose << " of " << n_bounded
      << " FRF values (low coherence): the confidence bounds are only indicative there";
    r.warnings.push_back(s.str());
  }
  return r;
}

inline void check_frf_options(const FrfOptions& o, const std::string& who) {
  if (!(o.confidence > 0.0 && o.confidence < 1.0)) throw std::invalid_argument(who + ": need 0 < confidence < 1");
  if (!(o.max_condition > 1.0)) throw std::invalid_argument(who + ": need max_condition > 1");
  if (!(o.quiet_input_ratio >= 0.0)) throw std::invalid_argument(who + ": need quiet_input_ratio >= 0");
}

inline Eigen::Index shortest_experiment(const IoData& data) {
  Eigen::Index n = std::numeric_limits<Eigen::Index>::max();
  for (const auto& e : data.experiments) n = std::min(n, e.samples());
  return n;
}

}  // namespace detail

/// Purpose: the l x m FRF matrix of a system from input/output records with all
/// inputs driven (simultaneously, or in any set of experiments whose pooled input
/// spectral matrix is well conditioned), with coherences and confidence bounds.
/// Method: file comment (B&P ch. 6-9). Spectra are averaged over all segments of all
/// experiments (segments never straddle two experiments).
/// Preconditions (std::invalid_argument): data valid (IoData::validate) with m >= 1,
/// l >= 1; Welch preconditions (spectral/welch.hpp) with N = the shortest experiment
/// (nfft is halved until it fits it); 0 < confidence < 1; max_condition > 1; for H2
/// with m > 1: l == m.
/// Numerical aspects: O(K (m + l) nfft log nfft + K nfft (m + l)^2 / 2) for the
/// spectra (each channel transformed once per segment), O(nfft (m^3 + m^2 l)) for the
/// per-frequency solves. Ill-conditioned G_uu is flagged, not thrown: see warnings.
/// Example: `FrfResult r = frf(data, {.welch = {.nfft = 4096}});`
inline FrfResult frf(const IoData& data, const FrfOptions& options = {}) {
  const std::string who = "frf";
  data.validate();
  detail::check_frf_options(options, who);
  const Eigen::Index m = data.inputs(), l = data.outputs();
  if (m < 1 || l < 1) throw std::invalid_argument(who + ": need inputs >= 1 and outputs >= 1");
  if (options.estimator == FrfEstimator::h2 && m > 1 && l != m)
    throw std::invalid_argument(who + ": H2 with m > 1 inputs needs outputs == inputs (have " + std::to_string(l) +
                                " outputs, " + std::to_string(m) + " inputs)");
  const double fs = 1.0 / data.Ts;
  const detail::SegmentPlan plan = detail::welch_plan(detail::shortest_experiment(data), fs, options.welch, who);
  std::vector<std::size_t> all(data.experiments.size());
  for (std::size_t e = 0; e < all.size(); ++e) all[e] = e;
  const bool full_yy = options.estimator == FrfEstimator::h2 && m > 1;
  return detail::solve_frf(detail::frf_spectra(data, all, -1, full_yy, plan, fs), options, true);
}

/// Convenience overload for one record: u (N x m), y (N x l), sampling frequency fs.
template <class DerivedU, class DerivedY>
FrfResult frf(const Eigen::MatrixBase<DerivedU>& u, const Eigen::MatrixBase<DerivedY>& y, double fs_hz,
              const FrfOptions& options = {}) {
  if (!(fs_hz > 0.0) || !std::isfinite(fs_hz)) throw std::invalid_argument("frf: need 0 < fs < infinity");
  return frf(IoData(Eigen::MatrixXd(u), Eigen::MatrixXd(y), 1.0 / fs_hz), options);
}

/// Purpose: the l x m FRF matrix from one-input-at-a-time experiments: each
/// experiment drives one input (options.excited_input, or the input of largest
/// variance); column j is the SISO estimate (H1 or H2) of all outputs against input j
/// over the experiments driving it (their segments averaged together).
/// Method: file comment. multiple_coherence is left empty (0 x 0): the columns come
/// from different experiments. segments and dof are per column.
/// Preconditions (std::invalid_argument): as frf(); excited_input empty or one entry
/// per experiment, each in [0, m); every input driven by at least one experiment.
/// A warning names every experiment whose other inputs are not quiet (RMS ratio >
/// quiet_input_ratio): its column is then biased and frf() should be used.
inline FrfResult frf_one_at_a_time(const IoData& data, const FrfOptions& options = {}) {
  const std::string who = "frf_one_at_a_time";
  data.validate();
  detail::check_frf_options(options, who);
  const Eigen::Index m = data.inputs(), l = data.outputs();
  if (m < 1 || l < 1) throw std::invalid_argument(who + ": need inputs >= 1 and outputs >= 1");
  const std::size_t ne = data.experiments.size();
  if (!options.excited_input.empty() && options.excited_input.size() != ne)
    throw std::invalid_argument(who + ": need excited_input.size() == number of experiments (" + std::to_string(ne) + ")");
  std::vector<std::vector<std::size_t>> by_input(static_cast<std::size_t>(m));
  std::vector<std::string> warnings;
  for (std::size_t e = 0; e < ne; ++e) {
    const Experiment& ex = data.experiments[e];
    const Eigen::VectorXd rms =
        ((ex.u.rowwise() - ex.u.colwise().mean()).colwise().squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, ex.samples())))
            .cwiseSqrt()
            .transpose();
    Eigen::Index j = 0;
    if (options.excited_input.empty()) rms.maxCoeff(&j);
    else j = options.excited_input[e];
    if (j < 0 || j >= m)
      throw std::invalid_argument(who + ": need 0 <= excited_input[" + std::to_string(e) + "] < " + std::to_string(m));
    by_input[static_cast<std::size_t>(j)].push_back(e);
    for (Eigen::Index k = 0; k < m; ++k)
      if (k != j && rms(k) > options.quiet_input_ratio * rms(j)) {
        std::ostringstream s;
        s << "experiment " << e + 1 << (ex.source.empty() ? "" : " (" + ex.source + ")") << " drives " << data.input_name(j)
          << " but " << data.input_name(k) << " has " << (rms(j) > 0 ? rms(k) / rms(j) : INFINITY)
          << " of its RMS: column " << data.input_name(j) << " is biased; use frf() (pooled MIMO H1)";
        warnings.push_back(s.str());
      }
  }
  for (Eigen::Index j = 0; j < m; ++j)
    if (by_input[static_cast<std::size_t>(j)].empty())
      throw std::invalid_argument(who + ": need every input driven by at least one experiment (" + data.input_name(j) +
                                  " is driven by none)");
  const double fs = 1.0 / data.Ts;
  const detail::SegmentPlan plan = detail::welch_plan(detail::shortest_experiment(data), fs, options.welch, who);
  FrfResult r;
  for (Eigen::Index j = 0; j < m; ++j) {
    const FrfResult c =
        detail::solve_frf(detail::frf_spectra(data, by_input[static_cast<std::size_t>(j)], j, false, plan, fs), options, false);
    if (j == 0) {
      r = c;
      for (std::size_t b = 0; b < c.H.size(); ++b) {
        for (auto* v : {&r.coherence, &r.random_error, &r.magnitude_lower, &r.magnitude_upper, &r.phase_halfwidth_rad})
          (*v)[b].resize(l, m);
        r.H[b].resize(l, m);
      }
      r.input_psd.resize(c.input_psd.rows(), m);
      r.multiple_coherence.resize(0, 0);
      r.segments.assign(static_cast<std::size_t>(m), 0);
      r.dof.resize(m);
      r.warnings.clear();
    }
    for (std::size_t b = 0; b < c.H.size(); ++b) {
      r.H[b].col(j) = c.H[b].col(0);
      r.coherence[b].col(j) = c.coherence[b].col(0);
      r.random_error[b].col(j) = c.random_error[b].col(0);
      r.magnitude_lower[b].col(j) = c.magnitude_lower[b].col(0);
      r.magnitude_upper[b].col(j) = c.magnitude_upper[b].col(0);
      r.phase_halfwidth_rad[b].col(j) = c.phase_halfwidth_rad[b].col(0);
      if (c.ill_conditioned[b]) r.ill_conditioned[b] = true;
    }
    r.input_psd.col(j) = c.input_psd.col(0);
    r.segments[static_cast<std::size_t>(j)] = c.segments.front();
    r.dof(j) = c.dof(0);
    for (const auto& w : c.warnings) r.warnings.push_back(data.input_name(j) + ": " + w);
  }
  // Output PSDs of the first column's experiments are kept; a per-column output PSD is not meaningful.
  r.input_condition = Eigen::VectorXd::Ones(r.freq_hz.size());
  r.warnings.insert(r.warnings.begin(), warnings.begin(), warnings.end());
  return r;
}

}  // namespace sysid
