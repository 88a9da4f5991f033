// Implementation of validate/residual_analysis.hpp (method and references in the header).
#include <sysid/validate/residual_analysis.hpp>
#include <sysid/core/ljung_box.hpp>

#include <sysid/core/distributions.hpp>
#include <sysid/core/format_lags.hpp>
#include <sysid/core/format_number.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

Eigen::MatrixXd model_residuals(const StateSpace& sys, const Eigen::MatrixXd& K, const Experiment& data,
                                CompareOptions options) {
  options.predict_steps = K.size() == 0 ? 0 : 1;
  const CompareResult r = compare(sys, K, data, options);
  return data.y - r.y_hat;
}

ResidualAnalysisResult analyze_residuals(const Eigen::MatrixXd& e, const Eigen::MatrixXd& u,
                                         const ResidualAnalysisOptions& options) {
  const Eigen::Index N = e.rows(), l = e.cols(), m = u.cols(), M = options.max_lag;
  if (l < 1) throw std::invalid_argument("analyze_residuals: need at least 1 residual channel");
  if (u.rows() != N && !(m == 0))
    throw std::invalid_argument("analyze_residuals: need u.rows() == e.rows() (" + std::to_string(u.rows()) +
                                " != " + std::to_string(N) + ")");
  if (M < 1) throw std::invalid_argument("analyze_residuals: need max_lag >= 1");
  if (N <= M)
    throw std::invalid_argument("analyze_residuals: need samples > max_lag (" + std::to_string(N) +
                                " <= " + std::to_string(M) + ")");
  if (!(options.confidence > 0.0 && options.confidence < 1.0))
    throw std::invalid_argument("analyze_residuals: need 0 < confidence < 1");
  const Eigen::Index h = options.ljung_box_lags == 0 ? M : options.ljung_box_lags;
  if (h < 1 || h >= N) throw std::invalid_argument("analyze_residuals: need 1 <= ljung_box_lags < samples");
  if (options.noise_parameters < 0 || options.noise_parameters >= h)
    throw std::invalid_argument("analyze_residuals: need 0 <= noise_parameters < ljung_box_lags (" +
                                std::to_string(options.noise_parameters) + " vs " + std::to_string(h) + ")");
  if (options.variance_lags < 0 || options.variance_lags >= N)
    throw std::invalid_argument("analyze_residuals: need 0 <= variance_lags < samples");
  if (!options.output_names.empty() && static_cast<Eigen::Index>(options.output_names.size()) != l)
    throw std::invalid_argument("analyze_residuals: need output_names empty or of size " + std::to_string(l));
  if (!options.input_names.empty() && static_cast<Eigen::Index>(options.input_names.size()) != m)
    throw std::invalid_argument("analyze_residuals: need input_names empty or of size " + std::to_string(m));
  if (!e.allFinite()) throw std::invalid_argument("analyze_residuals: need finite residuals");
  if (!u.allFinite()) throw std::invalid_argument("analyze_residuals: need finite inputs");

  const double alpha = 1.0 - options.confidence;
  const double sqrt_n = std::sqrt(static_cast<double>(N));
  const Eigen::Index K = std::min<Eigen::Index>(options.variance_lags == 0 ? std::max<Eigen::Index>(M, 25)
                                                                           : options.variance_lags,
                                                N - 1);
  const Eigen::Index auto_lags = std::max({M, h, K});  // autocorrelations needed by any part

  auto out_name = [&](Eigen::Index i) {
    return options.output_names.empty() ? "y" + std::to_string(i + 1) : options.output_names[i];
  };
  auto in_name = [&](Eigen::Index j) {
    return options.input_names.empty() ? "u" + std::to_string(j + 1) : options.input_names[j];
  };

  ResidualAnalysisResult r;
  r.samples = N;
  r.max_lag = M;
  r.confidence = options.confidence;
  r.z = normal_quantile(1.0 - alpha / 2.0);
  r.autocorrelation_bound = r.z / sqrt_n;
  if (N < 10 * M)
    r.warnings.push_back("only " + std::to_string(N) + " samples for lags up to " + std::to_string(M) +
                         ": the bounds are asymptotic (N >> max_lag) and rough here");

  // Centred channels, and their full autocorrelations up to auto_lags.
  Eigen::MatrixXd ec = e, uc = u;
  r.mean = e.colwise().mean().transpose();
  ec.rowwise() -= r.mean.transpose();
  if (m > 0) uc.rowwise() -= u.colwise().mean();
  r.rms = (ec.colwise().squaredNorm() / static_cast<double>(N)).cwiseSqrt().transpose();
  Eigen::MatrixXd acf_e(auto_lags + 1, l), acf_u(auto_lags + 1, m);
  for (Eigen::Index i = 0; i < l; ++i) {
    acf_e.col(i) = sample_correlation(ec.col(i), ec.col(i), 0, auto_lags);
    if (!(r.rms(i) > 0.0)) {
      r.warnings.push_back("the residual of " + out_name(i) + " is constant: its correlations are undefined (reported as 0)");
    } else if (std::abs(r.mean(i)) > r.z * r.rms(i) / sqrt_n) {
      r.warnings.push_back("the residual of " + out_name(i) + " has a mean of " + format_number(r.mean(i), 2) +
                           " (" + format_number(r.mean(i) / r.rms(i), 2) +
                           " rms), outside its bound: an offset the model does not explain");
    }
  }
  for (Eigen::Index j = 0; j < m; ++j) {
    acf_u.col(j) = sample_correlation(uc.col(j), uc.col(j), 0, auto_lags);
    if (acf_u(0, j) == 0.0)
      r.warnings.push_back("input " + in_name(j) + " is constant: its cross-correlation is undefined (reported as 0)");
  }
  r.autocorrelation = acf_e.topRows(M + 1);

  // Residual correlations between outputs (the diagonal is the autocorrelation).
  r.output_correlation.assign(static_cast<std::size_t>(M + 1), Eigen::MatrixXd::Zero(l, l));
  for (Eigen::Index i = 0; i < l; ++i)
    for (Eigen::Index j = 0; j < l; ++j) {
      const Eigen::VectorXd c = i == j ? Eigen::VectorXd(acf_e.col(i).head(M + 1)) : sample_correlation(ec.col(i), ec.col(j), 0, M);
      for (Eigen::Index tau = 0; tau <= M; ++tau) r.output_correlation[static_cast<std::size_t>(tau)](i, j) = c(tau);
    }

  // Residual-input cross-correlations with Bartlett's variance factor.
  r.input_correlation.resize(2 * M + 1, l * m);
  r.input_correlation_bound.resize(l * m);
  r.input_variance_factor.resize(l * m);
  for (Eigen::Index i = 0; i < l; ++i)
    for (Eigen::Index j = 0; j < m; ++j) {
      const Eigen::Index col = i * m + j;
      r.input_correlation.col(col) = sample_correlation(ec.col(i), uc.col(j), -M, M);
      // P = sum_{|k|<=K} r_e(k) r_u(k) = 1 + 2 sum_{k=1}^K r_e(k) r_u(k).
      double P = 1.0 + 2.0 * acf_e.col(i).segment(1, K).dot(acf_u.col(j).segment(1, K));
      if (!(P > 0.0)) {
        // The truncated sum of sample products can dip below zero only when both
        // signals have large oscillating correlations; the Bartlett-weighted sum
        // (a spectral estimate at frequency 0, never negative) replaces it.
        double Pb = 1.0;
        for (Eigen::Index k = 1; k <= K; ++k)
          Pb += 2.0 * (1.0 - static_cast<double>(k) / static_cast<double>(K + 1)) * acf_e(k, i) * acf_u(k, j);
        r.warnings.push_back("variance factor for " + out_name(i) + " vs " + in_name(j) +
                             " was not positive with rectangular truncation; the Bartlett-weighted sum was used");
        P = Pb > 0.0 ? Pb : 1.0;
      }
      r.input_variance_factor(col) = P;
      r.input_correlation_bound(col) = r.z * std::sqrt(P) / sqrt_n;
    }

  // Ljung-Box.
  r.ljung_box_lags = h;
  r.ljung_box_dof = static_cast<double>(h - options.noise_parameters);
  r.ljung_box_q.resize(l);
  r.ljung_box_p.resize(l);
  for (Eigen::Index i = 0; i < l; ++i) {
    const LjungBoxTest test = ljung_box_test(acf_e.col(i), N, h, options.noise_parameters);
    r.ljung_box_q(i) = test.statistic;
    r.ljung_box_p(i) = test.p_value;
  }

  // Verdicts.
  const double z_sim_auto = normal_quantile(1.0 - alpha / (2.0 * static_cast<double>(M)));
  const double z_sim_cross = normal_quantile(1.0 - alpha / (2.0 * static_cast<double>(2 * M + 1)));
  const std::string pct = detail::percent(options.confidence);
  r.verdicts.resize(static_cast<std::size_t>(l));
  for (Eigen::Index i = 0; i < l; ++i) {
    ResidualVerdict& v = r.verdicts[static_cast<std::size_t>(i)];
    bool strong = false;
    for (Eigen::Index tau = 1; tau <= M; ++tau) {
      const double a = std::abs(acf_e(tau, i));
      if (a > r.autocorrelation_bound) v.lags_outside.push_back(tau);
      if (a > z_sim_auto / sqrt_n) strong = true;
    }
    v.output_lags_outside.assign(static_cast<std::size_t>(l), {});
    bool strong_cross = false;
    for (Eigen::Index j = 0; j < l; ++j) {
      if (j == i) continue;
      for (Eigen::Index tau = 1; tau <= M; ++tau) {
        const double a = std::abs(r.output_correlation[static_cast<std::size_t>(tau)](i, j));
        if (a > r.autocorrelation_bound) v.output_lags_outside[static_cast<std::size_t>(j)].push_back(tau);
        if (a > z_sim_auto / sqrt_n) strong_cross = true;
      }
    }
    const bool lb_rejects = r.ljung_box_p(i) < alpha;
    v.white = !(lb_rejects || strong || strong_cross);
    const std::string lb_text = "Ljung-Box p = " + format_number(r.ljung_box_p(i), 2);
    if (v.white) {
      v.whiteness = "white";
      if (!v.lags_outside.empty())
        v.whiteness += " (autocorrelation outside the " + pct + " bound only at " + detail::lag_word(v.lags_outside) +
                       detail::format_lags(v.lags_outside) + ", as chance allows among " + std::to_string(M) + " lags)";
    } else {
      std::vector<std::string> why;
      if (!v.lags_outside.empty())
        why.push_back("autocorrelation outside the " + pct + " bound at " + detail::lag_word(v.lags_outside) +
                      detail::format_lags(v.lags_outside));
      if (lb_rejects) why.push_back(lb_text + " < " + format_number(alpha, 2));
      for (Eigen::Index j = 0; j < l; ++j) {
        const auto& lags = v.output_lags_outside[static_cast<std::size_t>(j)];
        if (!lags.empty())
          why.push_back("correlated with the earlier residual of " + out_name(j) + " at " + detail::lag_word(lags) +
                        detail::format_lags(lags));
      }
      v.whiteness = "not white: ";
      for (std::size_t k = 0; k < why.size(); ++k) v.whiteness += (k ? "; " : "") + why[k];
    }

    v.independent.assign(static_cast<std::size_t>(m), true);
    v.input_lags_outside.assign(static_cast<std::size_t>(m), {});
    v.independence.assign(static_cast<std::size_t>(m), "");
    for (Eigen::Index j = 0; j < m; ++j) {
      const Eigen::Index col = i * m + j;
      auto& lags = v.input_lags_outside[static_cast<std::size_t>(j)];
      const double sigma = std::sqrt(r.input_variance_factor(col)) / sqrt_n;
      bool dependent = false;
      for (Eigen::Index tau = -M; tau <= M; ++tau) {
        const double a = std::abs(r.input_correlation(tau + M, col));
        if (a > r.input_correlation_bound(col)) lags.push_back(tau);
        if (a > z_sim_cross * sigma) dependent = true;
      }
      v.independent[static_cast<std::size_t>(j)] = !dependent;
      std::string& text = v.independence[static_cast<std::size_t>(j)];
      if (acf_u(0, j) == 0.0) {
        text = "not tested against input " + in_name(j) + " (constant over the record)";
      } else if (!dependent) {
        text = "independent of input " + in_name(j);
        if (!lags.empty())
          text += " (outside the " + pct + " bound only at " + detail::lag_word(lags) + detail::format_lags(lags) +
                  ", as chance allows among " + std::to_string(2 * M + 1) + " lags)";
      } else {
        text = "correlated with input " + in_name(j) + " at " + detail::lag_word(lags) + detail::format_lags(lags);
        Eigen::Index peak = 0;
        r.input_correlation.col(col).cwiseAbs().maxCoeff(&peak);
        peak -= M;
        const bool negative = std::any_of(lags.begin(), lags.end(), [](Eigen::Index t) { return t < 0; });
        const bool positive = std::any_of(lags.begin(), lags.end(), [](Eigen::Index t) { return t >= 0; });
        // A coloured input spreads a correlation at one lag over its neighbours on
        // both sides (r_eu = g * r_uu), so negative lags next to a positive peak
        // are not by themselves evidence of feedback, and vice versa.
        text += " (peak at lag " + std::to_string(peak) + "; ";
        if (positive && !negative)
          text += "lags >= 0: input dynamics the model misses)";
        else if (negative && !positive)
          text += "lags < 0: the residual leads the input: feedback)";
        else if (peak >= 0)
          text += "lags >= 0: input dynamics the model misses; the negative lags may be its spread through a coloured "
                  "input, or feedback)";
        else
          text += "lags < 0: the residual leads the input: feedback; the lags >= 0 may be its spread through a coloured "
                  "input, or input dynamics the model misses)";
      }
    }
  }
  return r;
}

}  // namespace sysid
