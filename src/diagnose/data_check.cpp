// Pre-flight data check (see include/sysid/diagnose/data_check.hpp).
#include "sysid/diagnose/data_check.hpp"

#include <sysid/core/format_number.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "sysid/core/input_collinearity.hpp"
#include "sysid/core/median.hpp"
#include "sysid/core/persistent_excitation.hpp"
#include "sysid/pem/arx.hpp"
#include "sysid/pem/prediction_error.hpp"
#include "sysid/signal/polynomial_filter.hpp"
#include "sysid/core/distributions.hpp"
#include "sysid/validate/residual_analysis.hpp"

namespace sysid {

namespace {

/// Mean, std, offset, trend and clipping of one channel.
ChannelCheck channel_statistics(const std::string& name, const Eigen::VectorXd& x) {
  ChannelCheck c;
  c.name = name;
  const auto n = static_cast<double>(x.size());
  c.mean = x.mean();
  c.std = std::sqrt((x.array() - c.mean).square().sum() / n);
  c.offset_ratio = c.std > 0.0 ? std::abs(c.mean) / c.std : (c.mean != 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
  // Linear trend by QR on [1, t] (t scaled to [0, 1] for conditioning).
  Eigen::MatrixXd regressors(x.size(), 2);
  regressors.col(0).setOnes();
  regressors.col(1) = Eigen::VectorXd::LinSpaced(x.size(), 0.0, 1.0);
  const Eigen::Vector2d fit = regressors.colPivHouseholderQr().solve(x);
  const Eigen::VectorXd detrended = x - regressors * fit;
  const double detrended_std = std::sqrt(detrended.squaredNorm() / n);
  c.trend_ratio = detrended_std > 0.0 ? std::abs(fit(1)) / detrended_std : 0.0;
  const double hi = x.maxCoeff(), lo = x.minCoeff(), tolerance = 1e-9 * (hi - lo);
  Eigen::Index at_extreme = 0;
  for (Eigen::Index t = 0; t < x.size(); ++t) at_extreme += (x(t) >= hi - tolerance) || (x(t) <= lo + tolerance);
  c.clipped_share = hi > lo ? static_cast<double>(at_extreme) / n : 0.0;
  return c;
}

/// The input prewhitened by its own AR(prewhitening_order) model, or empty when
/// the filter leaves it coloured (Ljung-Box at level 1 % over feedback_lags lags):
/// a multisine or a band-limited input, which no AR filter whitens.
Eigen::VectorXd prewhitened_input(const IoData& data, Eigen::Index j, const DataCheckOptions& o, Eigen::VectorXd& filter) {
  const Experiment& e = data.experiments.front();
  const Eigen::Index N = e.samples();
  IoData single;
  single.Ts = data.Ts;
  single.experiments.push_back({Eigen::MatrixXd(N, 0), e.u.col(j), e.source});
  ArOptions aro;
  aro.na = o.prewhitening_order;
  try {
    filter = ar(single, aro).models.front().A;
  } catch (const std::exception&) {
    return {};
  }
  const Eigen::VectorXd uw = filter_polynomial(filter, Eigen::VectorXd::Ones(1), e.u.col(j)).col(0).tail(N - filter.size());
  const Eigen::Index lags = std::min<Eigen::Index>(o.feedback_lags, uw.size() - 1);
  const Eigen::VectorXd r = sample_correlation(uw, uw, 1, lags);
  const auto n = static_cast<double>(uw.size());
  double q = 0.0;
  for (Eigen::Index k = 0; k < lags; ++k) q += r(k) * r(k) / (n - static_cast<double>(k + 1));
  q *= n * (n + 2.0);
  return chi_square_sf(q, static_cast<double>(lags)) >= 0.01 ? uw : Eigen::VectorXd();
}

/// The feedback tests (file comment), each at half the family-wise level:
///  - the one-step residuals eps_i of the ARX fit against the inputs' future values
///    u_j(t + k), k = 1..feedback_lags, with Bartlett's coloured-signal variance
///    (validate/residual_analysis.hpp): valid for any input;
///  - where the input's own AR filter whitens it, the prewhitened input's future
///    against the equally filtered output (the classical test, which also sees a
///    loop whose noise is small: the controller's law itself).
void feedback_test(const IoData& data, const LinearPolynomialResult& fit, const DataCheckOptions& o, DataCheckResult& r,
                   std::vector<std::string>& serious) {
  const Experiment& e = data.experiments.front();
  const Eigen::Index N = e.samples(), m = e.u.cols(), l = e.y.cols();
  // The first noise_model_order predictions use the zeros before the record.
  const Eigen::Index skip = o.noise_model_order, used = N - skip;
  const Eigen::MatrixXd u = e.u.rowwise() - fit.input_offset.transpose();
  Eigen::MatrixXd residuals(used, l);
  for (Eigen::Index i = 0; i < l; ++i) {
    const Eigen::VectorXd y = e.y.col(i).array() - fit.output_offset(i);
    residuals.col(i) = prediction_errors(fit.models[static_cast<std::size_t>(i)], u, y, false).eps.tail(used);
  }
  ResidualAnalysisOptions ro;
  ro.max_lag = std::min<Eigen::Index>(o.feedback_lags, used - 1);
  ro.confidence = o.confidence;
  const ResidualAnalysisResult a = analyze_residuals(residuals, u.bottomRows(used), ro);
  const Eigen::Index lags = a.max_lag;
  r.feedback_lags = lags;
  const double z = normal_quantile(1.0 - (1.0 - o.confidence) / (4.0 * static_cast<double>(lags * m * l)));
  for (Eigen::Index j = 0; j < m; ++j) {
    Eigen::VectorXd filter;
    const Eigen::VectorXd uw = r.inputs[static_cast<std::size_t>(j)].std > 0.0 ? prewhitened_input(data, j, o, filter) : Eigen::VectorXd();
    for (Eigen::Index i = 0; i < l; ++i) {
      const Eigen::Index column = i * m + j;
      FeedbackCheck f;
      f.input = j;
      f.output = i;
      // Row lags - k holds r(eps_i(t - k), u_j(t)): the input k samples after the residual.
      for (Eigen::Index k = 1; k <= lags; ++k) {
        const double c = std::abs(a.input_correlation(lags - k, column));
        if (c > f.largest_correlation) {
          f.largest_correlation = c;
          f.at_lag = k;
        }
      }
      f.bound = z * a.input_correlation_bound(column) / a.z;
      f.likely = f.largest_correlation > f.bound;
      std::string evidence = "correlation " + format_number(f.largest_correlation, 2) +
                             " of the input with the output's earlier innovation at lag " + std::to_string(f.at_lag) +
                             ", bound " + format_number(f.bound, 2);
      if (uw.size() > 0) {
        const Eigen::VectorXd yw =
            filter_polynomial(filter, Eigen::VectorXd::Ones(1), e.y.col(i)).col(0).tail(uw.size());
        const Eigen::VectorXd corr = sample_correlation(uw, yw, 1, std::min<Eigen::Index>(lags, uw.size() - 1));
        Eigen::Index at = 0;
        f.prewhitened_correlation = corr.cwiseAbs().maxCoeff(&at);
        f.prewhitened_bound = z / std::sqrt(static_cast<double>(uw.size()));
        if (f.prewhitened_correlation > f.prewhitened_bound && !f.likely) {
          f.likely = true;
          evidence = "prewhitened correlation " + format_number(f.prewhitened_correlation, 2) + " at lag " +
                     std::to_string(at + 1) + ", bound " + format_number(f.prewhitened_bound, 2);
        }
      }
      if (f.likely)
        serious.push_back("input " + data.input_name(j) + " depends on past values of output " + data.output_name(i) + " (" +
                          evidence +
                          "): likely closed-loop data; output-error and subspace methods are then biased — use a "
                          "prediction-error model with a noise model (ARX, ARMAX) or an external reference");
      r.feedback.push_back(f);
    }
  }
}

}  // namespace

DataCheckResult check_data(const IoData& data, const Eigen::VectorXd& time, const DataCheckOptions& o) {
  data.validate();
  const Experiment& e = data.experiments.front();
  const Eigen::Index N = e.samples(), m = e.u.cols(), l = e.y.cols();
  if (o.max_excitation_order < 1 || o.noise_model_order < 1 || o.prewhitening_order < 1 || o.feedback_lags < 1)
    throw std::invalid_argument("check_data: need orders and lags >= 1");
  if (!(o.confidence > 0.0 && o.confidence < 1.0)) throw std::invalid_argument("check_data: need 0 < confidence < 1");
  const Eigen::Index needed = 4 * (o.max_excitation_order + o.noise_model_order);
  if (N < needed)
    throw std::invalid_argument("check_data: need at least " + std::to_string(needed) + " samples (have " +
                                std::to_string(N) + ")");
  DataCheckResult r;
  r.samples = N;
  std::vector<std::string> serious, advisory;

  for (Eigen::Index j = 0; j < m; ++j) {
    ChannelCheck c = channel_statistics(data.input_name(j), e.u.col(j));
    if (c.std > 0.0) {
      ExcitationOrderOptions eo;
      eo.max_order = o.max_excitation_order;
      eo.tolerance = o.excitation_tolerance;
      eo.max_samples = o.excitation_samples;
      ExcitationOrder pe = excitation_order(data, j, eo);
      c.excitation_order = pe.order;
      c.excitation_singular_values = std::move(pe.singular_values);
    }
    if (c.excitation_order == 0)
      serious.push_back("input " + c.name + " is constant: it excites nothing, and no model of its effect can be identified");
    else if (c.excitation_order < o.max_excitation_order)
      serious.push_back("input " + c.name + " is persistently exciting of order " + std::to_string(c.excitation_order) +
                        " only: it can determine at most " + std::to_string(c.excitation_order) +
                        " parameters of its path (a model of order about " + std::to_string(c.excitation_order / 2) +
                        "); " + (c.excitation_order <= 2 ? "a single sine reveals one frequency point, not a model"
                                                         : "add frequencies to the excitation"));
    r.inputs.push_back(std::move(c));
  }

  for (auto& w : collinear_input_warnings(data, "")) serious.push_back(std::move(w));

  // SNR per output from ARX(n, n) on all inputs (noise variance of each output
  // model); the same fit's residuals carry the feedback test.
  std::vector<double> noise_variance(static_cast<std::size_t>(l), std::numeric_limits<double>::quiet_NaN());
  if (m > 0) {
    ArxOptions ao;
    ao.na = o.noise_model_order;
    ao.nb.assign(static_cast<std::size_t>(m), o.noise_model_order);
    ao.nk.assign(static_cast<std::size_t>(m), 0);
    try {
      const LinearPolynomialResult fit = arx(data, ao);
      for (Eigen::Index i = 0; i < l; ++i) noise_variance[static_cast<std::size_t>(i)] = fit.models[static_cast<std::size_t>(i)].noise_variance;
      feedback_test(data, fit, o, r, serious);
    } catch (const std::exception& ex) {
      advisory.push_back(std::string("no signal-to-noise estimate and no feedback test: the ARX fit failed (") + ex.what() + ")");
    }
  }
  for (Eigen::Index i = 0; i < l; ++i) {
    ChannelCheck c = channel_statistics(data.output_name(i), e.y.col(i));
    const double lambda = noise_variance[static_cast<std::size_t>(i)], var = c.std * c.std;
    c.snr_db = std::isfinite(lambda) && lambda > 0.0 && var > lambda ? 10.0 * std::log10((var - lambda) / lambda)
                                                                     : std::numeric_limits<double>::quiet_NaN();
    if (std::isfinite(c.snr_db) && c.snr_db < 10.0)
      serious.push_back("output " + c.name + " has a signal-to-noise ratio of about " + format_number(c.snr_db, 2) +
                        " dB: parameter variances will be large; excite harder or record longer");
    if (c.std == 0.0) serious.push_back("output " + c.name + " is constant: nothing to identify");
    r.outputs.push_back(std::move(c));
  }

  for (auto* channels : {&r.inputs, &r.outputs}) {
    const bool is_input = channels == &r.inputs;
    for (const ChannelCheck& c : *channels) {
      const std::string what = std::string(is_input ? "input " : "output ") + c.name;
      if (c.clipped_share >= o.clipping_share && c.clipped_share * static_cast<double>(N) >= 5.0)
        serious.push_back(what + " sits at its extreme value in " + format_number(100.0 * c.clipped_share, 2) +
                          " % of the samples: likely clipped (sensor or amplifier range); a linear model will be biased — "
                          "reduce the amplitude or drop the clipped stretches");
      if (c.std > 0.0 && c.offset_ratio > o.offset_ratio)
        advisory.push_back(what + " has an offset of " + format_number(c.mean, 3) + " (" + format_number(c.offset_ratio, 2) +
                           " standard deviations): remove it (the verbs remove means) or model it");
      if (c.trend_ratio > o.trend_ratio)
        advisory.push_back(what + " drifts by " + format_number(c.trend_ratio, 2) +
                           " standard deviations over the record: detrend it (sysid filter --detrend linear), "
                           "or the drift is fitted as slow dynamics");
    }
  }

  if (time.size() > 1) {
    SamplingCheck& s = r.sampling;
    s.checked = true;
    Eigen::VectorXd steps = time.tail(time.size() - 1) - time.head(time.size() - 1);
    s.median_step = median(std::vector<double>(steps.data(), steps.data() + steps.size()));
    for (Eigen::Index k = 0; k < steps.size(); ++k) {
      if (!(steps(k) > 0.0)) ++s.non_increasing;
      if (s.median_step > 0.0) {
        s.max_jitter = std::max(s.max_jitter, std::abs(steps(k) - s.median_step) / s.median_step);
        if (steps(k) > 1.5 * s.median_step) ++s.gaps;
      }
    }
    if (s.non_increasing > 0)
      serious.push_back("the time column goes backwards or repeats at " + std::to_string(s.non_increasing) +
                        " step(s): the log is spliced or corrupted");
    if (s.gaps > 0)
      serious.push_back("the time column has " + std::to_string(s.gaps) +
                        " gap(s) longer than 1.5 sample times: samples were lost; identify on the stretches between gaps");
    else if (s.max_jitter > 0.01)
      advisory.push_back("the sample time varies by up to " + format_number(100.0 * s.max_jitter, 2) +
                         " %: timing jitter acts like noise at high frequencies");
  }

  r.findings = serious;
  r.findings.insert(r.findings.end(), advisory.begin(), advisory.end());
  return r;
}

std::string DataCheckResult::report() const {
  std::ostringstream s;
  s << samples << " samples\n";
  s << "inputs:\n";
  for (const auto& c : inputs)
    s << "  " << c.name << ": mean " << format_number(c.mean, 3) << ", std " << format_number(c.std, 3) << ", excitation order "
      << c.excitation_order << ", trend " << format_number(c.trend_ratio, 2) << " std, at extremes "
      << format_number(100.0 * c.clipped_share, 2) << " %\n";
  s << "outputs:\n";
  for (const auto& c : outputs)
    s << "  " << c.name << ": mean " << format_number(c.mean, 3) << ", std " << format_number(c.std, 3) << ", SNR "
      << (std::isfinite(c.snr_db) ? format_number(c.snr_db, 3) + " dB (upper estimate)" : std::string("n/a")) << ", trend "
      << format_number(c.trend_ratio, 2) << " std, at extremes " << format_number(100.0 * c.clipped_share, 2) << " %\n";
  if (!feedback.empty()) {
    s << "feedback test (input vs the output's earlier innovation, lags 1.." << feedback_lags << "):\n";
    for (const auto& f : feedback)
      s << "  " << (f.input < static_cast<Eigen::Index>(inputs.size()) ? inputs[static_cast<std::size_t>(f.input)].name : "?")
        << " <- past " << (f.output < static_cast<Eigen::Index>(outputs.size()) ? outputs[static_cast<std::size_t>(f.output)].name : "?")
        << ": largest |r| " << format_number(f.largest_correlation, 2) << " at lag " << f.at_lag << " (bound " << format_number(f.bound, 2)
        << ")" << (f.likely ? " LIKELY FEEDBACK" : "") << "\n";
  }
  if (sampling.checked)
    s << "sampling: median step " << format_number(sampling.median_step, 6) << " s, jitter " << format_number(100.0 * sampling.max_jitter, 2)
      << " %, gaps " << sampling.gaps << "\n";
  if (findings.empty())
    s << "findings: none — the log looks fit for identification\n";
  else {
    s << "findings:\n";
    for (std::size_t k = 0; k < findings.size(); ++k) s << "  " << k + 1 << ". " << findings[k] << "\n";
  }
  return s.str();
}

}  // namespace sysid
