// Implementation of reduce/reduction_error.hpp (method in the header).
#include "reduce/detail/reduction_error.hpp"
#include <sysid/reduce/reduction_error.hpp>
#include <sysid/core/math_constants.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

namespace {

void check_comparable(const StateSpace& a, const StateSpace& b) {
  if (a.Ts != b.Ts) throw std::invalid_argument("reduction_error: need equal Ts of the two models");
  if (a.inputs() != b.inputs() || a.outputs() != b.outputs())
    throw std::invalid_argument("reduction_error: need equal numbers of inputs and outputs");
}

}  // namespace

namespace detail {

double max_singular_value(const Eigen::MatrixXcd& G) {
  if (G.size() == 0) return 0.0;
  if (!G.allFinite()) return std::numeric_limits<double>::infinity();
  if (G.rows() == 1 || G.cols() == 1) return G.norm();
  const Eigen::MatrixXcd gram = G.rows() <= G.cols() ? Eigen::MatrixXcd(G * G.adjoint()) : Eigen::MatrixXcd(G.adjoint() * G);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es(gram, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff()));
}

}  // namespace detail

std::string ReductionResult::brief_report() const {
  char buf[256];
  std::string s = method + ": order " + std::to_string(original_order) + " -> " + std::to_string(order);
  if (unstable_states > 0) s += " (" + std::to_string(unstable_states) + " unstable states kept)";
  s += "\n";
  if (!std::isnan(error_ratio)) {
    std::snprintf(buf, sizeof buf, "  discarded HSV ratio %.6g, H-inf bound 2*sum(discarded HSV) = %.6g\n",
                  error_ratio, hinf_bound);
    s += buf;
  }
  if (!std::isnan(hinf_error)) {
    std::snprintf(buf, sizeof buf, "  H-inf error (grid of %ld points) %.6g at %.6g Hz; DC error %.6g\n",
                  static_cast<long>(grid_points), hinf_error, hinf_error_freq_hz, dc_error);
    s += buf;
  }
  for (const std::string& w : warnings) s += "  warning: " + w + "\n";
  return s;
}

Eigen::VectorXd error_frequency_grid(const Eigen::VectorXcd& poles, double Ts, const ErrorGridOptions& options) {
  if (options.log_points < 2) throw std::invalid_argument("error_frequency_grid: need log_points >= 2");
  if (!(options.decades_below > 0.0)) throw std::invalid_argument("error_frequency_grid: need decades_below > 0");
  std::vector<double> peak, width;
  double f_min = std::numeric_limits<double>::infinity(), f_max = 0.0;
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    const std::complex<double> p = poles[i];
    if (Ts > 0.0 && p == 0.0) continue;  // a pure delay: flat response, nothing to resolve
    const std::complex<double> s = Ts > 0.0 ? std::log(p) / Ts : p;
    const double fn = std::abs(s) / kTwoPi;
    if (!std::isfinite(fn)) continue;
    if (fn > 0.0) f_min = std::min(f_min, fn);
    f_max = std::max(f_max, fn);
    if (p.imag() > 0.0) {
      peak.push_back(std::abs(s.imag()) / kTwoPi);
      width.push_back(std::abs(s.real()) / kTwoPi);
    }
  }
  double f_hi = Ts > 0.0 ? 0.5 / Ts : (f_max > 0.0 ? 10.0 * f_max : 1.0);
  if (!std::isfinite(f_min) || f_min > f_hi) f_min = f_hi;
  const double f_lo = f_min * std::pow(10.0, -options.decades_below);
  std::vector<double> grid;
  grid.reserve(static_cast<std::size_t>(options.log_points) + 2 + 13 * peak.size());
  grid.push_back(0.0);
  const double l0 = std::log10(f_lo), l1 = std::log10(f_hi);
  for (int k = 0; k < options.log_points; ++k)
    grid.push_back(std::pow(10.0, l0 + (l1 - l0) * k / (options.log_points - 1)));
  grid.push_back(f_hi);
  static constexpr double offsets[] = {0.0, 0.125, -0.125, 0.25, -0.25, 0.5, -0.5, 1.0, -1.0, 2.0, -2.0, 4.0, -4.0};
  for (std::size_t i = 0; i < peak.size(); ++i)
    for (double o : offsets) {
      const double f = peak[i] + o * width[i];
      if (f >= 0.0 && f <= f_hi) grid.push_back(f);
      if (width[i] == 0.0) break;  // marginal pole: the single point
    }
  std::sort(grid.begin(), grid.end());
  grid.erase(std::unique(grid.begin(), grid.end()), grid.end());
  return Eigen::Map<const Eigen::VectorXd>(grid.data(), static_cast<Eigen::Index>(grid.size()));
}

HinfErrorEstimate reduction_error(const StateSpace& full, const StateSpace& reduced,
                                  const ErrorGridOptions& options) {
  full.validate();
  reduced.validate();
  check_comparable(full, reduced);
  const Eigen::VectorXcd p_full = poles(full), p_red = poles(reduced);
  Eigen::VectorXcd all(p_full.size() + p_red.size());
  all << p_full, p_red;
  const Eigen::VectorXd grid = error_frequency_grid(all, full.Ts, options);
  const std::vector<Eigen::MatrixXcd> g = frequency_response(full, grid);
  const std::vector<Eigen::MatrixXcd> gr = frequency_response(reduced, grid);
  HinfErrorEstimate e;
  e.grid_points = grid.size();
  e.value = -1.0;
  for (Eigen::Index i = 0; i < grid.size(); ++i) {
    const double s = detail::max_singular_value(g[static_cast<std::size_t>(i)] - gr[static_cast<std::size_t>(i)]);
    if (i == 0) e.dc = s;
    if (s > e.value || std::isnan(s)) {
      e.value = std::isnan(s) ? std::numeric_limits<double>::infinity() : s;
      e.freq_hz = grid[i];
    }
  }
  if (!full.is_discrete()) {
    const double s_inf = detail::max_singular_value((full.D - reduced.D).cast<std::complex<double>>());
    if (s_inf > e.value) {
      e.value = s_inf;
      e.freq_hz = std::numeric_limits<double>::infinity();
    }
  }
  return e;
}

HinfErrorEstimate hinf_norm_estimate(const StateSpace& error_system, const ErrorGridOptions& options) {
  StateSpace zero(Eigen::MatrixXd(0, 0), Eigen::MatrixXd(0, error_system.inputs()),
                  Eigen::MatrixXd(error_system.outputs(), 0),
                  Eigen::MatrixXd::Zero(error_system.outputs(), error_system.inputs()), error_system.Ts);
  return reduction_error(error_system, zero, options);
}

}  // namespace sysid
