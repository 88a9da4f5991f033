#pragma once
/// @file
/// Purpose: the one piece of code that measures how far a reduced model is from
/// the full one, ||G - G_r||_inf = sup_f sigma_max(G(f) - G_r(f)), and the Result
/// type every reduction method returns (ReductionResult), so balanced truncation,
/// singular perturbation and modal truncation report their errors the same way.
///
/// Method: sigma_max of the difference of the two frequency responses
/// (core/frequency_response.hpp, Laub 1981) on a dense grid:
///  - log-spaced: `log_points` points from f_lo to f_hi, plus f = 0 and f_hi.
///    Discrete: f_hi = Nyquist 1/(2 Ts); continuous: f_hi = 10 x the largest natural
///    frequency of any pole (and sigma_max(D - D_r), the value at infinity).
///    f_lo = 10^-decades_below x the smallest positive natural frequency.
///  - refined at every complex pole of either model: with s the continuous-time
///    equivalent of the pole (log(z)/Ts if discrete), a resonance peaks near
///    f_p = |Im s|/(2 pi) with half-power half-width w = |Re s|/(2 pi); the points
///    f_p + w {0, +-1/8, +-1/4, +-1/2, +-1, +-2, +-4} are added.
/// The grid maximum is a lower estimate of the true norm. Where the peak is one
/// resonance, |G| ~ 1/|j(f - f_p) + w| near it and the largest distance to a grid
/// point within +-w/4 is w/16, so the estimate is low by at most
/// 1 - 1/sqrt(1 + 1/16^2) ~ 0.2 %; elsewhere the log spacing (e.g. 400 points over
/// 6 decades: ratio 1.035) resolves a response that varies on the scale of the
/// poles' own half-widths, which the refinement covers.
///
/// Preconditions: both models valid, same Ts and the same numbers of inputs and
/// outputs (std::invalid_argument otherwise).
/// Numerical aspects: O(n^3) once plus O(n^2 m) per grid point for each model;
/// sigma_max from the eigenvalues of the smaller Gram matrix of each l x m
/// difference (absolute accuracy eps sigma_max^2 in sigma_max^2, plenty for the
/// largest singular value). A pole exactly on the grid gives an infinite error.
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

struct ErrorGridOptions {
  int log_points = 400;        ///< log-spaced points between f_lo and f_hi (>= 2)
  double decades_below = 3.0;  ///< f_lo = 10^-decades_below x the smallest positive pole frequency (> 0)
};

/// Peak of sigma_max(G - G_r) over the grid.
struct HinfErrorEstimate {
  double value = 0.0;    ///< max over the grid (a lower estimate of the H-infinity norm)
  double freq_hz = 0.0;  ///< where it occurs (Inf: at infinite frequency, continuous only)
  double dc = 0.0;       ///< sigma_max at f = 0 (the static gain error)
  Eigen::Index grid_points = 0;
};

/// The Result every reduction method returns (balanced_truncation.hpp,
/// modal_truncation.hpp). Fields that a method does not produce stay NaN/empty.
struct ReductionResult {
  StateSpace model;            ///< the reduced model (same Ts, inputs, outputs, names)
  std::string method;          ///< "balanced truncation", "singular perturbation", "modal truncation"
  Eigen::Index original_order = 0;
  Eigen::Index order = 0;            ///< order of `model`
  Eigen::Index unstable_states = 0;  ///< states of the unstable part, kept whole
  Eigen::VectorXd hsv;               ///< Hankel singular values of the stable part, descending (balanced methods)
  /// (sum of all HSV - sum of kept HSV) / sum of all HSV (the isolator paper's ratio).
  double error_ratio = std::numeric_limits<double>::quiet_NaN();
  /// 2 x sum of the discarded HSV: ||G - G_r||_inf <= hinf_bound (balanced methods).
  double hinf_bound = std::numeric_limits<double>::quiet_NaN();
  /// ||G - G_r||_inf measured on the grid (reduction_error.hpp), NaN if not measured.
  double hinf_error = std::numeric_limits<double>::quiet_NaN();
  double hinf_error_freq_hz = std::numeric_limits<double>::quiet_NaN();
  double dc_error = std::numeric_limits<double>::quiet_NaN();  ///< sigma_max(G(0) - G_r(0))
  Eigen::Index grid_points = 0;
  std::vector<Mode> kept_modes, removed_modes;  ///< modal truncation only
  std::vector<std::string> warnings;

  /// One line per figure, for logs and the CLI.
  std::string brief_report() const {
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
};

namespace detail {

/// sigma_max of a small complex matrix from its smaller Gram matrix.
inline double max_singular_value(const Eigen::MatrixXcd& G) {
  if (G.size() == 0) return 0.0;
  if (!G.allFinite()) return std::numeric_limits<double>::infinity();
  if (G.rows() == 1 || G.cols() == 1) return G.norm();
  const Eigen::MatrixXcd gram = G.rows() <= G.cols() ? Eigen::MatrixXcd(G * G.adjoint()) : Eigen::MatrixXcd(G.adjoint() * G);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es(gram, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff()));
}

inline void check_comparable(const StateSpace& a, const StateSpace& b) {
  if (a.Ts != b.Ts) throw std::invalid_argument("reduction_error: need equal Ts of the two models");
  if (a.inputs() != b.inputs() || a.outputs() != b.outputs())
    throw std::invalid_argument("reduction_error: need equal numbers of inputs and outputs");
}

}  // namespace detail

/// Purpose: the frequency grid described in the file comment, for a set of poles
/// (z if Ts > 0, s if Ts = 0). Sorted ascending, without duplicates, starting at 0.
/// Preconditions: Ts >= 0; options.log_points >= 2, options.decades_below > 0.
inline Eigen::VectorXd error_frequency_grid(const Eigen::VectorXcd& poles, double Ts, const ErrorGridOptions& options = {}) {
  if (options.log_points < 2) throw std::invalid_argument("error_frequency_grid: need log_points >= 2");
  if (!(options.decades_below > 0.0)) throw std::invalid_argument("error_frequency_grid: need decades_below > 0");
  constexpr double two_pi = 2.0 * std::numbers::pi;
  std::vector<double> peak, width;
  double f_min = std::numeric_limits<double>::infinity(), f_max = 0.0;
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    const std::complex<double> p = poles[i];
    if (Ts > 0.0 && p == 0.0) continue;  // a pure delay: flat response, nothing to resolve
    const std::complex<double> s = Ts > 0.0 ? std::log(p) / Ts : p;
    const double fn = std::abs(s) / two_pi;
    if (!std::isfinite(fn)) continue;
    if (fn > 0.0) f_min = std::min(f_min, fn);
    f_max = std::max(f_max, fn);
    if (p.imag() > 0.0) {
      peak.push_back(std::abs(s.imag()) / two_pi);
      width.push_back(std::abs(s.real()) / two_pi);
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

/// Purpose: ||G - G_r||_inf estimated on the grid of the file comment, built from
/// the poles of both models.
/// Preconditions: see the file comment.
inline HinfErrorEstimate reduction_error(const StateSpace& full, const StateSpace& reduced,
                                         const ErrorGridOptions& options = {}) {
  full.validate();
  reduced.validate();
  detail::check_comparable(full, reduced);
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

/// Purpose: ||E||_inf of an error system E = G - G_r given as one model (e.g. the
/// removed modes of a modal truncation), on the grid of its own poles.
inline HinfErrorEstimate hinf_norm_estimate(const StateSpace& error_system, const ErrorGridOptions& options = {}) {
  StateSpace zero(Eigen::MatrixXd(0, 0), Eigen::MatrixXd(0, error_system.inputs()),
                  Eigen::MatrixXd(error_system.outputs(), 0),
                  Eigen::MatrixXd::Zero(error_system.outputs(), error_system.inputs()), error_system.Ts);
  return reduction_error(error_system, zero, options);
}

}  // namespace sysid
