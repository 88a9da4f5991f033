#pragma once
/// @file
/// Purpose: locate where a nominal simulation model disagrees with a recorded log,
/// and decide whether it disagrees at all. Input: the log's inputs u (N x m) and
/// outputs y (N x l), the nominal model's simulated outputs y_nom (N x l) and its
/// simulation residual r = y - y_nom, sample time Ts. Every analysis is done per
/// output i (one ChannelLocation per output; the frequency-domain part covers all
/// inputs of that output jointly):
///
/// 1. Model-error FRF E_i(f) = residual_i / u (MIMO H1 from spectral/frf.hpp, i.e.
///    E^T = G_uu^{-1} G_ur) and its coherence. Null "no linear relation between u
///    and r_i": the joint (multiple) coherence estimate with n_d independent averages
///    is Beta(m, n_d - m) distributed (Goodman 1963; Carter, Knapp & Nuttall 1973,
///    IEEE Trans. Audio Electroacoust. 21, 337; for m = 1: P(gamma^2 > c) = (1 - c)^{n_d - 1}).
///    n_d = nu / 2 with nu Welch's equivalent degrees of freedom (overlapped segments
///    are not independent; see spectral/welch.hpp). Bins where it exceeds the
///    Bonferroni-corrected quantile (level alpha_f / number of analysed bins) are
///    "falsified"; contiguous ones (gaps <= band_merge_gap_bins) form a band. For a
///    single input this is exactly the region where the H1 confidence region of E
///    excludes 0. For m > 1 the band names the input contributing most residual
///    power at its peak (|E_ij|^2 G_{u_j u_j}).
/// 2. Narrow-band residual peaks: Welch PSD S_k of r_i against a local floor: a
///    least-squares quadratic in (j - k) fitted to ln S_j over the neighbours
///    g < |j - k| <= h_k (g the window's main-lobe half-width, so the peak's own lobe
///    is left out; h_k = min(floor_halfwidth_bins, max(g + 3, k / 2)): constant-Q
///    near DC, where a rational spectrum bends within a few bins of its corner), the
///    window mirrored at DC and Nyquist (a real signal's PSD is even), two passes
///    dropping outliers (other peaks), and the bias
///    E ln(chi2_nu/nu) = psi(nu/2) - ln(nu/2) removed. A running median was tried
///    first: it is biased wherever the spectrum curves (a low-pass knee, the DC end)
///    and gave ~40 % false alarms on AR(1) noise; the quadratic follows the curvature.
///    Under a smooth spectrum S_k / floor_k ~ F(nu, nu_floor), nu_floor = 2 / Var(ln
///    floor) from the fit's weights and the window's bin-to-bin correlation;
///    Bonferroni over the searched bins (those above the DC main lobe).
///    A peak is reported only where the joint coherence with the inputs is NOT
///    significant even pointwise (level alpha) and outside every falsified band.
///    Frequency: parabola through ln S at the peak bin and its neighbours;
///    amplitude = sqrt(2 P), P = sum over the main lobe (+-(g+1) bins) of
///    (S_k - floor) df (density scaling integrates to the variance; a sine of
///    amplitude A has variance A^2/2).
/// 3. Energy by time window: the record is cut into W windows; the mean square of the
///    (mean-removed) residual in each against the floor = median over the windows
///    (bias-corrected). A window's mean square of a Gaussian stationary residual has
///    nu_w = n / tau degrees of freedom (Satterthwaite), tau = sum_{|j|<n}
///    rho_r(j)^2 (1 - |j|/n) from the residual autocorrelation; the ratio to the floor
///    is tested against F(nu_w, nu_w W 2/pi) at level alpha_f / W (one-sided).
/// 4. Amplitude dependence: samples split by |y_nom - mean(y_nom)| into the lowest
///    `low_amplitude_quantile` and the highest 1 - `high_amplitude_quantile`; in each,
///    the least-squares slope (with intercept) of y on y_nom is the gain. The split is
///    by the nominal output, never by y: selecting on y = y_nom + r selects on r and
///    biases the gains under the null. gain_high - gain_low is a linear functional
///    sum_t w_t r_t of the residual; its variance is computed for a Gaussian stationary
///    residual from its Welch spectrum (below), so residual colour is accounted for.
///    A linear (Gaussian) mismatch gives the same slope in both sets (E[r | y_nom] is
///    linear), so this test reacts to nonlinearity, not to a gain error.
/// 5. Reversals: v = smoothed central difference of y_nom; reversals are its sign
///    changes. What is linear in the motion is partialled out first (LS on
///    [1, y_nom, v]): for a linear mismatch with Gaussian signals E[r | y_nom, v] is
///    linear, so what remains is null, whereas the raw correlation of r with sign(v)
///    is not (Bussgang: it is proportional to that with v). (a) mean square of that
///    remainder within +-k samples of a reversal minus elsewhere, variance from
///    Cov(r_s^2, r_t^2) = 2 R(s - t)^2 (Gaussian); (b) the coefficient of sign(v) in
///    the LS fit r ~ [1, y_nom, v, sign(v)] (a Coulomb-like step). Each two-sided at
///    alpha_f / 2.
/// 6. Position dependence: residual means in `position_bins` quantile bins of y_nom.
///    The test is on the departure of the bin means from the best straight line in
///    y_nom (the linear part is a gain error, which test 1 locates): the vector of
///    detrended bin means m = W r has covariance W C_r W^T; Q = m^T (W C_r W^T)^+ m
///    ~ chi2(B - 2), reported as f_statistic = Q / (B - 2) and tested against
///    F(B - 2, nu_var) (the covariance is estimated).
/// 7. Offset and drift: mean and least-squares slope of r_i against time, each a
///    t-test at alpha_f / 2 with its variance from the residual spectrum.
/// 8. Asymmetry (a one-sided or direction-dependent nonlinearity: a relief valve, a
///    one-sided stop, a gain that differs between push and pull): the part of r_i
///    that even functions of the inputs explain beyond the inputs themselves. The
///    inputs are extended by f_j = d_j^2 and |d_j|, d_j = u_j - mean(u_j) (each
///    centred; even about the operating point), and the partial
///    multiple coherence of r_i with the p extra channels given the m inputs,
///    (gamma^2_{r:[u f]} - gamma^2_{r:u}) / (1 - gamma^2_{r:u}) per bin (Bendat &
///    Piersol, Random Data, 4th ed., sec. 7.3), is tested against Beta(p, n_d - m - p)
///    (Goodman 1963) with Bonferroni over the analysed bins. Linear at each frequency
///    in u first, it stays null for a linear mismatch whatever the input; for inputs
///    with a symmetric distribution an odd nonlinearity (symmetric saturation,
///    dead zone, cubic) leaves it silent too, as even functions are uncorrelated with
///    odd ones, so a firing names an asymmetric effect. With few averages only the
///    squares are used (p = m); a binary input (PRBS), whose even functions are
///    constant, cannot be tested (`tested` false).
///
/// Variance of a linear functional T = sum_t x_t r_t (tests 4-7): for a stationary
/// residual with two-sided spectrum S2(f),
///   Var T = sum_k R(k) C_x(k) = int S2(f) |X(f)|^2 df ~ (1/M) sum_m fs S2(f_m) |X_m|^2,
/// X_m the M-point DFT of x, M >= N + nfft/2 so the autocorrelation of x is not
/// wrapped within the correlation time of r (taken < nfft/2 samples); S2 is the
/// residual's Welch spectrum (no per-segment detrend, so the DC bin is kept) linearly
/// interpolated to the fine grid. Its uncertainty is carried by Satterthwaite's
/// degrees of freedom of the estimated variance (Welch bins have nu, DC nu/2, adjacent
/// bins correlated as the window implies), and the test uses F(1, nu_eff) (a t-test)
/// instead of the normal.
///
/// Family-wise error: 8 families x l outputs, each tested at alpha_f = significance /
/// (8 l) and Bonferroni-corrected within the family (bins, windows, sub-tests), so
/// for a correct model (residual = stationary Gaussian noise, white or coloured,
/// independent of u, with correlation time well under nfft/2 samples and a spectrum
/// smooth over floor_halfwidth_bins) P(any_mismatch) <= significance up to the
/// approximations named above. Tests 4-6 are built to stay silent for a purely
/// linear mismatch with Gaussian signals (their statistics are null whenever
/// E[r | y_nom, v] is linear), so they point at nonlinearity; with non-Gaussian
/// excitation (multisines, PRBS) that holds only approximately. The families can
/// still fire together (a cubic term also shows as a gain error in test 1); the list
/// `fired` says which fired.
///
/// Preconditions (std::invalid_argument): rows(u) == rows(y) == rows(r) == rows(y_nom);
/// cols(y) == cols(r) == cols(y_nom) >= 1; cols(u) >= 1; finite samples; Ts > 0 finite;
/// N >= 8 nfft with nfft >= 16 (auto nfft: the largest power of two <= N / 8, capped
/// at 4096, so N >= 128); options as documented on each field.
///
/// Numerical aspects: O(N log N) per output for the spectra and the regressor DFTs
/// (about 20 real FFTs of size M ~ 2N), O(nfft * floor_halfwidth_bins^2) for the
/// local floor fits (their F quantiles memoised on the dof), plus one H1 fit with
/// m + p inputs for test 8 (shared by the outputs); N = 20000, nfft = 2048: ~30 ms
/// per output.
///
/// Implementation: src/diagnose/mismatch_location.cpp (the driver),
/// mismatch_tests_spectral.cpp (tests 1, 2 and 8), mismatch_tests_time.cpp (tests
/// 3-7), mismatch_spectral_variance.cpp (the variance of linear functionals); the
/// Beta and F distributions of the tests are in core/distributions.hpp.
#include <sysid/spectral/welch.hpp>
#include <sysid/spectral/window.hpp>

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

namespace sysid {

struct MismatchLocationOptions {
  /// FFT/segment length of the spectral estimates. 0: the largest power of two <=
  /// N / 8, capped at 4096. Otherwise >= 16 with N >= 8 nfft (>= ~15 averages).
  Eigen::Index nfft = 0;
  double overlap = 0.5;                  ///< Welch overlap, 0 <= overlap < 1
  WindowType window = WindowType::hann;  ///< Welch taper
  /// Family-wise level: P(any_mismatch | correct model) <= significance. 0 < significance < 1.
  double significance = 0.01;
  double min_freq_hz = 0.0;  ///< analysed band for tests 1-2 (DC and Nyquist bins always excluded)
  double max_freq_hz = std::numeric_limits<double>::infinity();  ///< > min_freq_hz
  Eigen::Index band_merge_gap_bins = 2;    ///< significant bins at most this many bins apart form one band; >= 0
  Eigen::Index floor_halfwidth_bins = 16;  ///< half-width of the local floor fit (test 2); >= main-lobe half-width + 3
  Eigen::Index time_windows = 20;          ///< W >= 3, with N / W >= 8
  double low_amplitude_quantile = 0.5;     ///< low set: |y_nom - mean| <= this quantile; 0 < low < high
  double high_amplitude_quantile = 0.9;    ///< high set: |y_nom - mean| >= this quantile; high < 1
  Eigen::Index velocity_smoothing = 5;     ///< moving-average length applied to the velocity, >= 1
  /// k: samples either side of a reversal counted as "near". 0: automatic, 10 % of
  /// the median spacing between reversals (at least 1). >= 0.
  Eigen::Index reversal_halfwidth = 0;
  Eigen::Index position_bins = 10;  ///< B >= 3 quantile bins of y_nom
  std::vector<std::string> input_names, output_names;  ///< for messages; empty: u1.., y1..
};

/// Contiguous frequency bins where the model-error FRF is significantly non-zero.
struct FalsifiedBand {
  double lo_hz = 0, hi_hz = 0;  ///< first and last significant bin
  double peak_hz = 0;           ///< bin of largest residual power explained by the input
  double peak_gain = 0;         ///< |E_ij| at the peak (residual units per input unit)
  double peak_coherence = 0;    ///< joint coherence at the peak
  Eigen::Index input = 0;       ///< input j (0-based) contributing most at the peak
  std::string input_name;       ///< its name (options.input_names, else u1, u2, ...)
};

/// Narrow-band residual peak not coherent with any input (hum, periodic disturbance).
struct ResidualPeak {
  double freq_hz = 0;        ///< refined by a parabola through ln S
  double amplitude = 0;      ///< estimated sine peak amplitude, residual units
  double prominence_db = 0;  ///< 10 log10(S_peak / floor)
};

struct ResidualWindow {
  /// [t0, t1): times (from the first sample, t = k Ts) of the window's first sample and one past its last
  double t0_s = 0, t1_s = 0;
  double energy_ratio = 0;    ///< mean square / floor
  bool flagged = false;
};

struct AmplitudeDependence {
  bool tested = false;  ///< false when y_nom has no spread (then nothing below is meaningful)
  double gain_low = 0, gain_high = 0;        ///< LS slope of y on y_nom in the low / high set
  double gain_low_se = 0, gain_high_se = 0;  ///< their standard errors (residual colour included)
  double z = 0;                              ///< (gain_high - gain_low) / its standard error
  double rms_ratio = 0;                      ///< RMS of r in the high set / in the low set
  bool flagged = false;
};

struct ReversalDependence {
  bool tested = false;             ///< false with fewer than 2 reversals or an empty near/far set
  Eigen::Index reversals = 0;      ///< sign changes of the smoothed nominal velocity
  Eigen::Index halfwidth = 0;      ///< k actually used
  double energy_ratio = 0;         ///< mean square of r near reversals / elsewhere
  double energy_z = 0;             ///< standardised difference of the two mean squares
  double sign_correlation = 0;     ///< raw correlation coefficient of r with sign(v) (for information)
  /// Coefficient of sign(v) in the LS fit r ~ [1, y_nom, v, sign(v)]: a step of
  /// 2 sign_level at each reversal beyond what is linear in the motion (residual units).
  double sign_level = 0;
  double sign_z = 0;               ///< sign_level / its standard error
  bool flagged = false;
};

struct PositionDependence {
  bool tested = false;
  Eigen::VectorXd bin_centres;          ///< mean y_nom in each quantile bin
  Eigen::VectorXd bin_means;            ///< mean residual in each bin
  Eigen::VectorXd bin_means_detrended;  ///< after removing the best line r ~ a + b y_nom (what is tested)
  double f_statistic = 0;               ///< Q / (B - 2)
  double p_value = 1;
  bool flagged = false;
};

/// Test 8: dependence of the residual on even functions of the inputs.
struct AsymmetryDependence {
  bool tested = false;        ///< false for a binary input or too few averages for the extra channels
  int regressors = 0;         ///< p: even functions used (d_j^2 and |d_j| per input, d_j = u_j - mean, or d_j^2 only)
  /// bins: partial multiple coherence of r with the even functions given u; NaN where not analysed
  Eigen::VectorXd partial_coherence;
  double threshold = 1;       ///< family-corrected threshold on partial_coherence
  double peak_hz = 0;         ///< bin of the largest partial coherence
  double peak_partial_coherence = 0;
  bool flagged = false;
};

struct OffsetDrift {
  double offset = 0, offset_se = 0;          ///< residual mean
  double slope_per_s = 0, slope_se = 0;      ///< LS slope of the residual against time
  bool flagged = false;
};

/// Everything found for one output (all inputs together).
struct ChannelLocation {
  std::string output;
  // Spectral part, one row per frequency bin k fs / nfft, k = 0..nfft/2.
  Eigen::VectorXd freq_hz;
  Eigen::MatrixXd model_error_gain;   ///< bins x m: |E_ij|
  Eigen::MatrixXd model_error_lower;  ///< bins x m: lower bound on |E_ij| at confidence 1 - significance
  Eigen::MatrixXd model_error_upper;  ///< bins x m: upper bound
  Eigen::MatrixXd coherence;          ///< bins x m: ordinary coherence of r_i with u_j
  Eigen::VectorXd joint_coherence;    ///< bins: multiple coherence (= ordinary for m = 1); NaN outside the analysed band
  double coherence_threshold = 1;     ///< family-corrected threshold on joint_coherence
  Eigen::VectorXd residual_psd;       ///< bins: Welch PSD of r_i, units^2/Hz
  Eigen::VectorXd residual_floor;     ///< bins: local floor (robust local quadratic in ln S, mean-corrected)
  /// bins: family-corrected threshold on residual_psd (inf outside the searched bins)
  Eigen::VectorXd residual_threshold;
  std::vector<FalsifiedBand> bands;
  std::vector<ResidualPeak> peaks;
  // Time-domain part.
  std::vector<ResidualWindow> windows;
  double window_threshold = 0;        ///< family-corrected threshold on energy_ratio
  AmplitudeDependence amplitude;
  ReversalDependence reversal;
  PositionDependence position;
  OffsetDrift offset;
  AsymmetryDependence asymmetry;
  double residual_rms = 0;            ///< about the mean
  /// Long-run variance factor of the residual, fs S2(0) / var = sum_k rho(k): 1 for
  /// white noise, > 1 for low-pass noise (how much fewer independent samples there are).
  double long_run_variance_factor = 1;
};

struct MismatchLocation {
  std::vector<ChannelLocation> outputs;  ///< one per output
  bool any_mismatch = false;             ///< some test of some family fired
  /// One entry per fired test family and output: "model_error:y1", "residual_peak:y1",
  /// "time_window:y1", "amplitude:y1", "reversal:y1", "position:y1", "offset_drift:y1",
  /// "asymmetry:y1".
  std::vector<std::string> fired;
  std::vector<std::string> warnings;
  Eigen::Index nfft = 0;
  Eigen::Index segments = 0;  ///< Welch averages K
  double dof = 0;             ///< Welch equivalent degrees of freedom nu (n_d = nu / 2)
  double family_level = 0;    ///< alpha_f = significance / (8 l)

  /// A few lines per output: bands, peaks, flagged windows and tests.
  std::string brief_report() const;
};

namespace detail {

MismatchLocation locate_mismatch_impl(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y, const Eigen::MatrixXd& residual,
                                      const Eigen::MatrixXd& y_nominal, double Ts, const MismatchLocationOptions& options);

}  // namespace detail

/// Purpose: locate the nominal model's mismatch in frequency, time, amplitude,
/// velocity sign and position, and decide whether there is any (file comment).
/// Method: file comment, tests 1-7, family-wise level `significance`.
/// Preconditions (std::invalid_argument): see the file comment.
/// Example:
///   Eigen::MatrixXd y_nom = simulate(nominal, u);
///   MismatchLocation loc = locate_mismatch(u, y, y - y_nom, y_nom, Ts);
///   if (!loc.any_mismatch) ... // the simulation is consistent with the log
template <class DU, class DY, class DR, class DN>
MismatchLocation locate_mismatch(const Eigen::MatrixBase<DU>& u, const Eigen::MatrixBase<DY>& y,
                                 const Eigen::MatrixBase<DR>& residual, const Eigen::MatrixBase<DN>& y_nominal, double Ts,
                                 const MismatchLocationOptions& options = {}) {
  return detail::locate_mismatch_impl(Eigen::MatrixXd(u), Eigen::MatrixXd(y), Eigen::MatrixXd(residual),
                                      Eigen::MatrixXd(y_nominal), Ts, options);
}

}  // namespace sysid
