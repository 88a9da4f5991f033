// Implementation of pem/arx.hpp (methods and references in the header).
#include <sysid/core/errors.hpp>
#include <sysid/pem/arx.hpp>
#include <sysid/core/identification_warnings.hpp>
#include <sysid/pem/lagged_regression.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include "pem/detail/pooled_autocorrelation.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>

namespace sysid {

namespace detail {

std::pair<Eigen::VectorXd, Eigen::VectorXd> remove_means_if(IoData& data, bool remove) {
  if (!remove) return {Eigen::VectorXd::Zero(data.inputs()), Eigen::VectorXd::Zero(data.outputs())};
  const ChannelOffsets off = remove_means(data);
  return {off.input, off.output};
}

std::vector<int> input_delays(const std::vector<int>& nk, Eigen::Index inputs) {
  if (nk.empty()) return std::vector<int>(static_cast<std::size_t>(inputs), 1);
  if (static_cast<Eigen::Index>(nk.size()) != inputs)
    throw std::invalid_argument("polynomial model: need one nk per input (" + std::to_string(nk.size()) + " given for " +
                                std::to_string(inputs) + " inputs)");
  for (int k : nk)
    if (k < 0) throw std::invalid_argument("polynomial model: need nk >= 0 (a negative delay is a non-causal model)");
  return nk;
}

namespace {

/// Signals of output r for the regression: column 0 = y_r, columns 1.. = inputs.
std::vector<Eigen::MatrixXd> output_signals(const IoData& data, Eigen::Index r, bool with_inputs) {
  std::vector<Eigen::MatrixXd> s;
  for (const auto& e : data.experiments) {
    Eigen::MatrixXd m(e.samples(), 1 + (with_inputs ? e.u.cols() : 0));
    m.col(0) = e.y.col(r);
    if (with_inputs) m.rightCols(e.u.cols()) = e.u;
    s.push_back(std::move(m));
  }
  return s;
}

/// The overdetermined modified Yule-Walker equations (Stoica & Moses 2005, eq.
/// 3.7.6): for k = na+1 .. na+M, sum_{j=1}^{na} a_j r(k - j) = -r(k); least squares
/// by column-pivoting QR. Returns A = [1, a_1 .. a_na].
Eigen::VectorXd modified_yule_walker(const Eigen::VectorXd& r, int na, int equations) {
  Eigen::MatrixXd R(equations, na);
  Eigen::VectorXd rhs(equations);
  for (int i = 0; i < equations; ++i) {
    const int k = na + 1 + i;
    for (int j = 1; j <= na; ++j) R(i, j - 1) = r(k - j);
    rhs(i) = -r(k);
  }
  Eigen::VectorXd a(na + 1);
  a << 1.0, R.colPivHouseholderQr().solve(rhs);
  return a;
}

/// Levinson-Durbin on autocorrelation r(0..na): A = [1, a_1..a_na] and the final prediction-error variance.
std::pair<Eigen::VectorXd, double> levinson_durbin(const Eigen::VectorXd& r, int na) {
  Eigen::VectorXd a = Eigen::VectorXd::Zero(na + 1);
  a(0) = 1.0;
  double error = r(0);
  for (int k = 1; k <= na; ++k) {
    double acc = r(k);
    for (int j = 1; j < k; ++j) acc += a(j) * r(k - j);
    const double reflection = -acc / error;
    const Eigen::VectorXd previous = a;
    for (int j = 1; j < k; ++j) a(j) = previous(j) + reflection * previous(k - j);
    a(k) = reflection;
    error *= (1.0 - reflection * reflection);
  }
  return {a, error};
}

/// Burg's recursion pooled over experiments (each series x_e): A and the prediction-error variance.
std::pair<Eigen::VectorXd, double> burg(const std::vector<Eigen::VectorXd>& series, int na) {
  std::vector<Eigen::VectorXd> f = series, b = series;
  Eigen::VectorXd a = Eigen::VectorXd::Zero(na + 1);
  a(0) = 1.0;
  double error = 0, count = 0;
  for (const auto& x : series) {
    error += x.squaredNorm();
    count += static_cast<double>(x.size());
  }
  error /= count;
  for (int k = 1; k <= na; ++k) {
    double num = 0, den = 0;
    for (std::size_t e = 0; e < series.size(); ++e) {
      const Eigen::Index n = f[e].size();
      // forward errors f(t), t = k..n-1 against backward errors b(t-1).
      num += f[e].segment(k, n - k).dot(b[e].segment(k - 1, n - k));
      den += f[e].segment(k, n - k).squaredNorm() + b[e].segment(k - 1, n - k).squaredNorm();
    }
    const double reflection = den > 0 ? -2.0 * num / den : 0.0;
    for (std::size_t e = 0; e < series.size(); ++e) {
      const Eigen::Index n = f[e].size();
      const Eigen::VectorXd f_old = f[e];
      for (Eigen::Index t = n - 1; t >= k; --t) {
        f[e](t) = f_old(t) + reflection * b[e](t - 1);
        b[e](t) = b[e](t - 1) + reflection * f_old(t);
      }
    }
    const Eigen::VectorXd previous = a;
    for (int j = 1; j < k; ++j) a(j) = previous(j) + reflection * previous(k - j);
    a(k) = reflection;
    error *= (1.0 - reflection * reflection);
  }
  return {a, error};
}

}  // namespace
}  // namespace detail

LinearPolynomialResult arx(IoData data, const ArxOptions& options) {
  data.validate();
  const Eigen::Index m = data.inputs(), l = data.outputs();
  if (options.na < 0) throw std::invalid_argument("arx: need na >= 0");
  if (static_cast<Eigen::Index>(options.nb.size()) != m)
    throw std::invalid_argument("arx: need one nb per input (" + std::to_string(options.nb.size()) + " given for " +
                                std::to_string(m) + " inputs)");
  for (int nb : options.nb)
    if (nb < 0) throw std::invalid_argument("arx: need nb >= 0");
  const std::vector<int> nk = detail::input_delays(options.nk, m);
  require_varying_inputs(data, "arx");
  LinearPolynomialResult out;
  {
    int nb_max = 0;
    for (int nb : options.nb) nb_max = std::max(nb_max, nb);
    out.warnings = identification_data_warnings(data, options.na + nb_max,
                                                "ARX(" + std::to_string(options.na) + ", " + std::to_string(nb_max) + ")", "arx");
  }
  std::tie(out.input_offset, out.output_offset) = detail::remove_means_if(data, options.remove_means);
  for (Eigen::Index r = 0; r < l; ++r) {
    std::vector<RegressionTerm> terms{{0, 1, options.na, -1.0}};
    for (Eigen::Index i = 0; i < m; ++i)
      terms.push_back({1 + i, nk[static_cast<std::size_t>(i)], options.nb[static_cast<std::size_t>(i)], 1.0});
    const RegressionSolution sol = lagged_least_squares(detail::output_signals(data, r, true), 0, terms);
    PolynomialModel model;
    model.Ts = data.Ts;
    model.A = Eigen::VectorXd(options.na + 1);
    model.A << 1.0, sol.theta.head(options.na);
    Eigen::Index at = options.na;
    for (Eigen::Index i = 0; i < m; ++i) {
      const int nb = options.nb[static_cast<std::size_t>(i)];
      model.B.push_back(sol.theta.segment(at, nb));
      model.nk.push_back(nk[static_cast<std::size_t>(i)]);
      model.F.push_back(Eigen::VectorXd::Ones(1));
      at += nb;
    }
    model.noise_variance = sol.residual_variance;
    out.models.push_back(std::move(model));
    out.covariance.push_back(sol.covariance);
    out.condition.push_back(sol.condition);
    if (sol.rank_deficient)
      out.warnings.push_back("arx: output '" + data.output_name(r) + "': the regressors are (nearly) collinear (condition " +
                             std::to_string(sol.condition) + "); the parameters are not determined by the data");
  }
  return out;
}

LinearPolynomialResult ar(IoData data, const ArOptions& options) {
  data.validate();
  if (options.na < 1) throw std::invalid_argument("ar: need na >= 1");
  const Eigen::Index l = data.outputs();
  LinearPolynomialResult out;
  std::tie(out.input_offset, out.output_offset) = detail::remove_means_if(data, options.remove_means);
  out.input_offset.resize(0);
  for (Eigen::Index r = 0; r < l; ++r) {
    PolynomialModel model;
    model.Ts = data.Ts;
    Eigen::MatrixXd cov;
    double condition = 0;
    if (options.method == ArMethod::least_squares) {
      const RegressionSolution sol = lagged_least_squares(detail::output_signals(data, r, false), 0, {{0, 1, options.na, -1.0}});
      model.A = Eigen::VectorXd(options.na + 1);
      model.A << 1.0, sol.theta;
      model.noise_variance = sol.residual_variance;
      cov = sol.covariance;
      condition = sol.condition;
    } else {
      std::vector<Eigen::VectorXd> series;
      Eigen::Index shortest = std::numeric_limits<Eigen::Index>::max();
      for (const auto& e : data.experiments) {
        series.push_back(e.y.col(r));
        shortest = std::min(shortest, e.samples());
      }
      if (shortest <= options.na) throw std::invalid_argument("ar: need more samples than na in every experiment");
      if (options.method == ArMethod::yule_walker) {
        // Biased autocorrelation (positive definite Toeplitz: stable A).
        const Eigen::VectorXd acf = detail::pooled_autocorrelation(series, options.na);
        if (!(acf(0) > 0)) throw DataError("ar: output '" + data.output_name(r) + "' is constant");
        std::tie(model.A, model.noise_variance) = detail::levinson_durbin(acf, options.na);
      } else if (options.method == ArMethod::modified_yule_walker) {
        const int equations = options.modified_yule_walker_equations > 0 ? options.modified_yule_walker_equations : 4 * options.na;
        if (shortest <= options.na + equations)
          throw std::invalid_argument("ar: the modified Yule-Walker method needs more samples than na + equations (" +
                                      std::to_string(options.na + equations) + ") in every experiment");
        const Eigen::VectorXd acf = detail::pooled_autocorrelation(series, options.na + equations);
        if (!(acf(0) > 0)) throw DataError("ar: output '" + data.output_name(r) + "' is constant");
        model.A = detail::modified_yule_walker(acf, options.na, equations);
        // Variance of A(q) y over every experiment, from the samples where every lag
        // lies inside the series (the first na of the filter output are its start-up).
        double sum = 0, count = 0;
        for (const auto& x : series) {
          const Eigen::VectorXd e = filter_polynomial(model.A, Eigen::VectorXd::Ones(1), x).col(0);
          sum += e.tail(x.size() - options.na).squaredNorm();
          count += static_cast<double>(x.size() - options.na);
        }
        model.noise_variance = sum / count;
      } else {
        std::tie(model.A, model.noise_variance) = detail::burg(series, options.na);
      }
    }
    out.models.push_back(std::move(model));
    out.covariance.push_back(cov);
    out.condition.push_back(condition);
  }
  return out;
}

}  // namespace sysid
