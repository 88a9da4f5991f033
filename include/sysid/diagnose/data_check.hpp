#pragma once
/// @file
/// Purpose: a pre-flight check of a log before any identification (`sysid check`):
/// what the data can support and what will go wrong, each with its consequence in
/// words — so an engineer fixes the experiment, not the model.
///
/// Per input: the excitation order (how many parameters of a linear model the
/// input can determine), offset, trend, clipping. Per output: a signal-to-noise
/// estimate, offset, trend, clipping. Per input-output pair: signs of feedback.
/// Of the time column (when given): irregular sampling and gaps.
///
/// Method:
/// - Excitation order: core/persistent_excitation.hpp (Hankel singular values of
///   the input, n = max_excitation_order columns, cut at the first 40 dB "cliff").
/// - Signal-to-noise: an ARX(na, nb) model of each output on all inputs (QR least
///   squares, pem/arx.hpp) with na = nb = noise_model_order; its one-step residual
///   variance lambda estimates the noise, SNR = (var y - lambda) / lambda. It
///   overstates the SNR when the noise is coloured (a predictor forecasts part of
///   it) — the report calls it an upper estimate.
/// - Offset: |mean| / std. Trend: the linear trend's change over the record
///   divided by the detrended std (least squares by QR on [1, t]).
/// - Clipping: the share of samples sitting at the channel's maximum or minimum
///   (within 1e-9 of the range); a real signal touches its extreme once.
/// - Feedback: in open loop the input does not depend on past outputs, so the
///   innovation of each output (the one-step residual of the ARX model above) is
///   uncorrelated with every later input value u(t + k), k >= 1; under feedback
///   u(t + k) depends on y(t) and so on its innovation (Ljung 1999 sec. 16.6:
///   residual-input correlation at negative lags; Söderström & Stoica, "System
///   Identification", sec. 12.5). The residual, not a prewhitened input, is what
///   makes the test valid for any input: an AR prewhitening filter cannot whiten a
///   multisine or a band-limited input (thousands of lines, no power above the
///   band), and the output's deterministic response to the input's own past then
///   correlated with its future — false alarms on open-loop data. The correlation's
///   variance is Bartlett's sum_k r_eps(k) r_u(k) / N (validate/residual_analysis.hpp),
///   valid for a coloured input and a residual that is not quite white; the level is
///   family-wise: Bonferroni over the feedback_lags lags, every input-output pair
///   and the two tests. The innovation carries little of a loop whose noise is
///   small (a force disturbance on a position loop moves the output's innovation
///   by C B d, a fraction of its effect); so where the input's own AR filter
///   whitens it (Ljung-Box at 1 %: a white or ARMA reference, not a multisine),
///   the classical test runs too: the prewhitened input's future against the
///   equally filtered output (zero for every k >= 1 in open loop). Not detected:
///   a controller that acts within the sample (u(t) from y(t), logged at the same
///   tick), which the data cannot tell from a plant's direct feedthrough.
/// - Sampling: the time column's steps against their median: jitter (largest
///   relative deviation) and gaps (steps longer than 1.5 times the median).
#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

#include "sysid/core/io_data.hpp"

namespace sysid {

struct DataCheckOptions {
  Eigen::Index max_excitation_order = 60;     ///< columns of the input's Hankel matrix
  double excitation_tolerance = 1e-3;         ///< singular values below this times the largest count as zero (60 dB)
  Eigen::Index excitation_samples = 20000;    ///< rows of the Hankel matrix used at most (from the start)
  int noise_model_order = 20;                 ///< ARX orders na = nb for the SNR estimate and the feedback test
  int prewhitening_order = 20;                ///< AR order of the input's prewhitening filter (second feedback test)
  Eigen::Index feedback_lags = 25;            ///< lags k = 1..feedback_lags tested
  double confidence = 0.99;                   ///< of the feedback test, family-wise (Bonferroni over the lags and pairs)
  double offset_ratio = 0.5;                  ///< |mean| / std above which an offset is reported
  double trend_ratio = 0.5;                   ///< trend change / std above which a trend is reported
  double clipping_share = 0.002;              ///< share of samples at an extreme that signals clipping
};

struct ChannelCheck {
  std::string name;
  double mean = 0.0, std = 0.0;
  double offset_ratio = 0.0;    ///< |mean| / std
  double trend_ratio = 0.0;     ///< |slope| * duration / std of the detrended signal
  double clipped_share = 0.0;   ///< share of samples at the maximum or the minimum
  Eigen::Index excitation_order = 0;  ///< inputs only
  Eigen::VectorXd excitation_singular_values;  ///< inputs only, relative to the largest
  double snr_db = 0.0;          ///< outputs only (upper estimate, see file comment)
};

struct FeedbackCheck {
  Eigen::Index input = 0, output = 0;
  double largest_correlation = 0.0;  ///< max |r(u(t + k), eps(t))|, k = 1..feedback_lags (eps: the output's ARX innovation)
  Eigen::Index at_lag = 0;
  double bound = 0.0;                ///< family-wise z times Bartlett's standard deviation
  /// The prewhitened test (file comment): max |r(u_w(t + k), y_w(t))| and its bound,
  /// NaN when the input's AR filter does not whiten it (the test is then invalid).
  double prewhitened_correlation = std::numeric_limits<double>::quiet_NaN();
  double prewhitened_bound = std::numeric_limits<double>::quiet_NaN();
  bool likely = false;
};

struct SamplingCheck {
  bool checked = false;         ///< a time column was given
  double median_step = 0.0;     ///< s
  double max_jitter = 0.0;      ///< max |step - median| / median
  Eigen::Index gaps = 0;        ///< steps longer than 1.5 median
  Eigen::Index non_increasing = 0;
};

struct DataCheckResult {
  Eigen::Index samples = 0;
  std::vector<ChannelCheck> inputs, outputs;
  std::vector<FeedbackCheck> feedback;
  Eigen::Index feedback_lags = 0;  ///< lags 1..feedback_lags tested (0: no test)
  SamplingCheck sampling;
  /// Each problem found with its consequence, in words, most serious first.
  std::vector<std::string> findings;
  /// The whole report as text (a table per channel, then the findings).
  std::string report() const;
};

/// Purpose: the pre-flight check of the first experiment of `data` (file comment);
/// `time` is the raw time column (empty when there is none).
/// Preconditions (std::invalid_argument): data.validate(); at least
/// 4 (max_excitation_order + noise_model_order) samples; options in range.
DataCheckResult check_data(const IoData& data, const Eigen::VectorXd& time = {}, const DataCheckOptions& options = {});

}  // namespace sysid
