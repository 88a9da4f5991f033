// Implementation of family/uncertainty_weight.hpp (method in the header): the
// section parametrisation, the starts from the bound's features, the
// Levenberg-Marquardt fits, the SQP refinement (NLopt's SLSQP) and the cascade
// realisation.
#include <sysid/family/uncertainty_weight.hpp>

#include <sysid/core/errors.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/levenberg_marquardt.hpp>
#include <sysid/core/math_constants.hpp>
#include <sysid/core/median.hpp>

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <exception>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sysid {

namespace {

using Complex = std::complex<double>;
using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// Box of the log-parameters (file comment, step 1). q_1 = exp(alpha) up to e^3 = 20
// puts a root at exp(-20) ~ 0; q_0 = exp(beta) <= 9.78 < pi^2 keeps a complex
// pair's angle below pi (no aliasing); exp(-30) ~ 1e-13 is a damping or corner far
// below anything a grid resolves.
constexpr double kLogMin = -30.0;
constexpr double kAlphaMax = 3.0;
constexpr double kBetaMax = 2.28;
constexpr double kGammaMax = 3.0;
constexpr double kLogGainMax = 60.0;

/// cos(sqrt(x)) for x >= 0, continued by cosh(sqrt(-x)) for x < 0 (an entire
/// function of x), and its derivative.
void cos_sqrt(double x, double& c, double& dc) {
  if (x > 1e-6) {
    const double s = std::sqrt(x);
    c = std::cos(s);
    dc = -std::sin(s) / (2.0 * s);
  } else if (x < -1e-6) {
    const double s = std::sqrt(-x);
    c = std::cosh(s);
    dc = -std::sinh(s) / (2.0 * s);
  } else {  // Taylor: 1 - x/2 + x^2/24 - x^3/720
    c = 1.0 - x / 2.0 + x * x / 24.0;
    dc = -0.5 + x / 12.0 - x * x / 240.0;
  }
}

/// sin^2(sqrt(x)) for x >= 0, -sinh^2(sqrt(-x)) for x < 0: 1 - cos_sqrt(x)^2
/// without its cancellation.
double sin_sqrt_squared(double x) {
  if (x >= 0.0) {
    const double s = std::sin(std::sqrt(x));
    return s * s;
  }
  const double s = std::sinh(std::sqrt(-x));
  return -s * s;
}

/// The monic quadratic z^2 + a1 z + a2 of (alpha, beta): roots exp(lambda - delta),
/// lambda^2 + exp(alpha) lambda + exp(beta) = 0; with the derivatives of a1, a2.
struct Quadratic {
  double a1 = 0, a2 = 0;
  double da1_dalpha = 0, da1_dbeta = 0, da2_dalpha = 0;
  double re = 0;    ///< half the root sum, -a1 / 2
  double disc = 0;  ///< a2 - re^2: > 0 complex pair (= imaginary part squared), < 0 real pair
};

Quadratic quadratic(double alpha, double beta, double delta) {
  const double q1 = std::exp(alpha), q0 = std::exp(beta);
  const double x = q0 - q1 * q1 / 4.0;
  double c = 0, dc = 0;
  cos_sqrt(x, c, dc);
  const double e = std::exp(-delta - q1 / 2.0);
  Quadratic q;
  q.a2 = e * e;
  q.a1 = -2.0 * e * c;
  q.da2_dalpha = -q1 * q.a2;
  // a1 = -2 e(q1) C(x(q1, q0)); de/dq1 = -e / 2, dx/dq1 = -q1 / 2, dq1/dalpha = q1.
  q.da1_dalpha = e * q1 * c + e * dc * q1 * q1;
  q.da1_dbeta = -2.0 * e * dc * q0;
  q.re = e * c;
  q.disc = e * e * sin_sqrt_squared(x);
  return q;
}

/// The real root exp(-delta - exp(gamma)) of a first-order factor.
double first_order_root(double gamma, double delta) { return std::exp(-delta - std::exp(gamma)); }

/// x = [log g, (alpha_z, beta_z, alpha_p, beta_p) per quadratic section,
///      (gamma_z, gamma_p) when the order is odd].
struct Layout {
  int quadratics = 0;
  bool first = false;
  Index size() const { return 1 + 4 * quadratics + (first ? 2 : 0); }
  Index first_index() const { return 1 + 4 * quadratics; }
  int order() const { return 2 * quadratics + (first ? 1 : 0); }
};

VectorXd lower_bounds(const Layout& layout) {
  VectorXd lo = VectorXd::Constant(layout.size(), kLogMin);
  lo(0) = -kLogGainMax;
  return lo;
}

VectorXd upper_bounds(const Layout& layout) {
  VectorXd hi(layout.size());
  hi(0) = kLogGainMax;
  for (int s = 0; s < layout.quadratics; ++s) hi.segment(1 + 4 * s, 4) << kAlphaMax, kBetaMax, kAlphaMax, kBetaMax;
  if (layout.first) hi.tail(2).setConstant(kGammaMax);
  return hi;
}

/// The grid points with bound > 0: angle theta = 2 pi f Ts (z = exp(j theta) =
/// cos + j sin), the log bound, and a log-frequency coordinate for windows.
struct Points {
  VectorXd theta, log_bound, logf;
  Eigen::ArrayXd cos, sin, cos2, sin2;  ///< of theta and 2 theta
  Index size() const { return theta.size(); }
};

/// log|W(z_k)| at every point, and d log|W(z_k)| / dx in J when J != nullptr
/// (d log|P| / d a1 = Re(z / P), d log|P| / d a2 = Re(1 / P), file comment).
void log_magnitude(const Layout& layout, const VectorXd& x, const Points& pts, double delta, VectorXd& lw,
                   MatrixXd* J) {
  using Eigen::ArrayXd;
  const Index N = pts.size();
  // prod |N_i|^2 / prod |D_i|^2 (one log per point at the end; |P|^2 lies in
  // [(1 - max_radius)^4, 16], so six factors neither overflow nor underflow).
  ArrayXd ratio = ArrayXd::Ones(N);
  if (J) {
    J->setZero(N, layout.size());
    J->col(0).setOnes();
  }
  for (int s = 0; s < layout.quadratics; ++s)
    for (int part = 0; part < 2; ++part) {  // zeros (+), poles (-)
      const Index i = 1 + 4 * s + 2 * part;
      const Quadratic q = quadratic(x(i), x(i + 1), delta);
      // P = z^2 + a1 z + a2 at z = cos + j sin.
      const ArrayXd re = pts.cos2 + q.a1 * pts.cos + q.a2;
      const ArrayXd im = pts.sin2 + q.a1 * pts.sin;
      const ArrayXd norm = re.square() + im.square();
      if (part == 0)
        ratio *= norm;
      else
        ratio /= norm;
      if (J) {
        const double sign = part == 0 ? 1.0 : -1.0;
        const ArrayXd inv_re = re / norm;                                // Re(1 / P)
        const ArrayXd z_inv_re = (pts.cos * re + pts.sin * im) / norm;  // Re(z / P)
        J->col(i) = sign * (z_inv_re * q.da1_dalpha + inv_re * q.da2_dalpha);
        J->col(i + 1) = sign * q.da1_dbeta * z_inv_re;
      }
    }
  if (layout.first)
    for (int part = 0; part < 2; ++part) {
      const Index i = layout.first_index() + part;
      const double p = first_order_root(x(i), delta), dp = -p * std::exp(x(i));
      const ArrayXd re = pts.cos - p;
      const ArrayXd norm = re.square() + pts.sin.square();
      if (part == 0)
        ratio *= norm;
      else
        ratio /= norm;
      if (J) J->col(i) = (part == 0 ? -dp : dp) * (re / norm);  // d log|z - p| / dp = -Re(1 / P)
    }
  lw = x(0) + 0.5 * ratio.log();
}

/// Mean of e - min(e): the mean log conservatism of the fit once shifted to cover.
double covering_score(const VectorXd& e) { return e.mean() - e.minCoeff(); }

// ---------------------------------------------------------------------------
// Levenberg-Marquardt stage: r_k = w_k e_k, w_k = 1 (e_k >= 0) or below_penalty.

class FitProblem final : public LevenbergMarquardt::Problem {
 public:
  FitProblem(const Layout& layout, const Points& pts, double delta, double penalty, VectorXd x)
      : m_layout(layout), m_pts(pts), m_delta(delta), m_penalty(penalty), m_x(std::move(x)),
        m_lo(lower_bounds(layout)), m_hi(upper_bounds(layout)) {}

  Index residual_count() const override { return m_pts.size(); }
  Index parameter_count() const override { return m_layout.size(); }
  VectorXd parameters() const override { return m_x; }
  double cost() override { return cost_at(m_x); }

  MatrixXd jacobian_factor() override {
    const Index N = m_pts.size(), n = m_layout.size();
    log_magnitude(m_layout, m_x, m_pts, m_delta, m_lw, &m_J);
    m_JR.resize(N, n + 1);
    for (Index k = 0; k < N; ++k) {
      const double e = m_lw(k) - m_pts.log_bound(k);
      const double w = e >= 0.0 ? 1.0 : m_penalty;
      m_JR.row(k).head(n) = w * m_J.row(k);
      m_JR(k, n) = w * e;
    }
    const Eigen::HouseholderQR<Eigen::Ref<MatrixXd>> qr(m_JR);  // in place
    MatrixXd R = MatrixXd::Zero(n + 1, n + 1);
    const Index rows = std::min(N, n + 1);
    R.topRows(rows) = qr.matrixQR().topRows(rows).triangularView<Eigen::Upper>();
    return R;
  }

  bool set_candidate(const VectorXd& x) override {
    if ((x.array() < m_lo.array()).any() || (x.array() > m_hi.array()).any() || !x.allFinite()) return false;
    m_candidate = x;
    return true;
  }
  double candidate_cost() override { return cost_at(m_candidate); }
  void accept_candidate() override { m_x = m_candidate; }

 private:
  double cost_at(const VectorXd& x) {
    log_magnitude(m_layout, x, m_pts, m_delta, m_lw, nullptr);
    double c = 0.0;
    for (Index k = 0; k < m_pts.size(); ++k) {
      const double e = m_lw(k) - m_pts.log_bound(k);
      const double r = e >= 0.0 ? e : m_penalty * e;
      c += r * r;
    }
    return std::isfinite(c) ? 0.5 * c : std::numeric_limits<double>::infinity();
  }

  const Layout& m_layout;
  const Points& m_pts;
  double m_delta, m_penalty;
  VectorXd m_x, m_candidate, m_lo, m_hi, m_lw;
  MatrixXd m_J, m_JR;
};

struct Fit {
  Layout layout;
  VectorXd x;  ///< shifted to cover the bound (min_k e_k = 0)
  double score = std::numeric_limits<double>::infinity();
  int iterations = 0;
};

/// Shifts log g so that min_k e_k = 0 and scores the fit.
Fit covering_fit(const Layout& layout, VectorXd x, const Points& pts, double delta, int iterations) {
  VectorXd lw;
  log_magnitude(layout, x, pts, delta, lw, nullptr);
  const VectorXd e = lw - pts.log_bound;
  Fit fit;
  fit.layout = layout;
  fit.iterations = iterations;
  if (!e.allFinite()) return fit;
  x(0) = std::clamp(x(0) - e.minCoeff(), -kLogGainMax, kLogGainMax);
  fit.x = x;
  fit.score = covering_score(e);
  return fit;
}

Fit lm_fit(const Layout& layout, const VectorXd& x0, const Points& pts, double delta,
           const UncertaintyWeightOptions& options) {
  FitProblem problem(layout, pts, delta, options.below_penalty, x0);
  LevenbergMarquardt::Options o;
  o.max_iterations = options.max_iterations;
  o.step_significance_tolerance = 0.0;  // not a statistical fit: no noise level to compare steps with
  o.function_tolerance = 1e-9;
  const LevenbergMarquardt::Summary s = LevenbergMarquardt::solve(problem, o);
  return covering_fit(layout, problem.parameters(), pts, delta, s.iterations);
}

// ---------------------------------------------------------------------------
// SQP refinement: minimise mean_k e_k subject to e_k >= 0 (NLopt LD_SLSQP).

struct SqpData {
  const Layout* layout = nullptr;
  const Points* pts = nullptr;
  double delta = 0.0;
  VectorXd x_cached, lw;
  MatrixXd J;
  bool valid = false;
  int evaluations = 0;
  VectorXd best_x;  ///< best covering score seen at any evaluated point
  double best_score = std::numeric_limits<double>::infinity();
  std::vector<Index> rows;  ///< the points constrained (all, or a working set on large grids)

  void evaluate(const double* x) {
    const Index n = layout->size();
    const Eigen::Map<const VectorXd> xv(x, n);
    if (valid && x_cached == xv) return;
    x_cached = xv;
    log_magnitude(*layout, x_cached, *pts, delta, lw, &J);
    valid = true;
    ++evaluations;
    const VectorXd e = lw - pts->log_bound;
    if (e.allFinite() && J.allFinite()) {
      const double score = covering_score(e);
      if (score < best_score) {
        best_score = score;
        best_x = x_cached;
      }
    }
  }
};

double sqp_objective(unsigned n, const double* x, double* grad, void* data) {
  auto* d = static_cast<SqpData*>(data);
  d->evaluate(x);
  const double N = static_cast<double>(d->pts->size());
  if (grad)
    for (unsigned j = 0; j < n; ++j) grad[j] = d->J.col(j).sum() / N;
  const double f = (d->lw - d->pts->log_bound).sum() / N;
  return std::isfinite(f) ? f : 1e30;
}

void sqp_constraints(unsigned m, double* result, unsigned n, const double* x, double* grad, void* data) {
  auto* d = static_cast<SqpData*>(data);
  d->evaluate(x);
  for (unsigned k = 0; k < m; ++k) {
    const Index row = d->rows[k];
    result[k] = d->pts->log_bound(row) - d->lw(row);
    if (grad)
      for (unsigned j = 0; j < n; ++j) grad[static_cast<std::size_t>(k) * n + j] = -d->J(row, j);
  }
}

/// Adds to `rows` (sorted, unique) the local minima of e and the `count` smallest
/// e_k that are below `below`.
void add_working_rows(std::vector<Index>& rows, const VectorXd& e, std::size_t count, double below) {
  const Index N = e.size();
  std::vector<Index> candidates;
  for (Index k = 0; k < N; ++k)
    if (e(k) < below) candidates.push_back(k);
  for (Index k : candidates)
    if ((k == 0 || e(k) <= e(k - 1)) && (k + 1 == N || e(k) <= e(k + 1))) rows.push_back(k);
  if (candidates.size() > count) {
    std::nth_element(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(count), candidates.end(),
                     [&](Index a, Index b) { return e(a) < e(b); });
    candidates.resize(count);
  }
  rows.insert(rows.end(), candidates.begin(), candidates.end());
  std::sort(rows.begin(), rows.end());
  rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
}

/// Grids up to this size constrain every point in the SQP; larger ones a working
/// set (local minima of e and the smallest e_k), grown by the points the previous
/// round left below the bound (at most kSqpRounds rounds).
constexpr Index kSqpAllRows = 600;
constexpr int kSqpRounds = 3;

Fit sqp_refine(const Fit& start, const Points& pts, double delta, int evaluations) {
  if (evaluations <= 0) return start;
  const Layout& layout = start.layout;
  const auto n = static_cast<unsigned>(layout.size());
  const Index N = pts.size();
  SqpData data;
  data.layout = &layout;
  data.pts = &pts;
  data.delta = delta;
  data.best_x = start.x;
  data.best_score = start.score;
  const VectorXd lo = lower_bounds(layout), hi = upper_bounds(layout);
  VectorXd lw;
  if (N <= kSqpAllRows) {
    data.rows.resize(static_cast<std::size_t>(N));
    for (Index k = 0; k < N; ++k) data.rows[static_cast<std::size_t>(k)] = k;
  } else {
    log_magnitude(layout, start.x, pts, delta, lw, nullptr);
    add_working_rows(data.rows, lw - pts.log_bound, static_cast<std::size_t>(kSqpAllRows) / 2,
                     std::numeric_limits<double>::infinity());
  }
  std::vector<double> x(start.x.data(), start.x.data() + n);
  for (int round = 0; round < kSqpRounds; ++round) {
    const auto m = static_cast<unsigned>(data.rows.size());
    nlopt::opt opt(nlopt::LD_SLSQP, n);
    opt.set_lower_bounds(std::vector<double>(lo.data(), lo.data() + n));
    opt.set_upper_bounds(std::vector<double>(hi.data(), hi.data() + n));
    opt.set_min_objective(sqp_objective, &data);
    opt.add_inequality_mconstraint(sqp_constraints, &data, std::vector<double>(m, 1e-9));
    opt.set_maxeval(std::max(1, evaluations - data.evaluations));
    opt.set_ftol_abs(1e-10);
    opt.set_xtol_rel(1e-10);
    double value = 0.0;
    try {
      opt.optimize(x, value);
    } catch (const std::exception&) {
      // Round-off limits or an SQP failure: the best point evaluated stands (data.best_x).
    }
    if (N <= kSqpAllRows || data.evaluations >= evaluations) break;
    // Points of the whole grid the working set left below the bound join it.
    const Eigen::Map<const VectorXd> xv(x.data(), n);
    log_magnitude(layout, xv, pts, delta, lw, nullptr);
    const VectorXd e = lw - pts.log_bound;
    const std::size_t before = data.rows.size();
    add_working_rows(data.rows, e, static_cast<std::size_t>(kSqpAllRows) / 4, -1e-6);
    if (data.rows.size() == before) break;
    x.assign(data.best_x.data(), data.best_x.data() + n);
    data.valid = false;
  }
  Fit fit = covering_fit(layout, data.best_x, pts, delta, start.iterations + data.evaluations);
  return fit.score <= start.score ? fit : Fit{start.layout, start.x, start.score, fit.iterations};
}

// ---------------------------------------------------------------------------
// Starts from the bound's features.

/// A peak (bound above its surroundings) or valley of a log curve: where, how high
/// (log ratio, > 0), the relative half-width at half the log height, and the
/// fraction of the grid points inside that width.
struct Feature {
  double theta = 0, height = 0, eps = 0, fraction = 0;
  bool peak = true;
};

/// Running median of v over the points within +-half_width of each point's logf.
VectorXd running_median(const Points& pts, const VectorXd& v, double half_width) {
  const Index N = pts.size();
  VectorXd out(N);
  Index lo = 0, hi = 0;
  std::vector<double> window;
  for (Index k = 0; k < N; ++k) {
    while (pts.logf(lo) < pts.logf(k) - half_width) ++lo;
    while (hi + 1 < N && pts.logf(hi + 1) <= pts.logf(k) + half_width) ++hi;
    window.assign(v.data() + lo, v.data() + hi + 1);
    out(k) = median(window);
  }
  return out;
}

/// Peaks and valleys of d (higher than `threshold` in log), one per hump: a local
/// extreme is dropped when a higher one lies within its half-height extent.
std::vector<Feature> features_of(const Points& pts, const VectorXd& d, double threshold) {
  std::vector<Feature> out;
  const Index N = pts.size();
  const double theta_max = pts.theta(N - 1);
  for (int pass = 0; pass < 2; ++pass) {
    const double sign = pass == 0 ? 1.0 : -1.0;
    for (Index k = 0; k < N; ++k) {
      const double h = sign * d(k);
      // Local extremes only (the walks below would drop the others).
      if (!(h > threshold) || (k > 0 && sign * d(k - 1) >= h) || (k + 1 < N && sign * d(k + 1) > h)) continue;
      bool dominated = false;
      Index l = k, r = k;
      while (l > 0 && sign * d(l - 1) > h / 2) {
        --l;
        if (sign * d(l) >= h) {
          dominated = true;
          break;
        }
      }
      if (dominated) continue;
      while (r + 1 < N && sign * d(r + 1) > h / 2) {
        ++r;
        if (sign * d(r) > h) {
          dominated = true;
          break;
        }
      }
      if (dominated) continue;
      // Half-height crossings, interpolated; a hump cut by the grid's end is measured
      // on its one side.
      auto crossing = [&](Index inside, Index outside) {
        const double a = sign * d(inside) - h / 2, b = h / 2 - sign * d(outside);
        return pts.theta(inside) + (pts.theta(outside) - pts.theta(inside)) * a / std::max(a + b, 1e-300);
      };
      const bool cut_left = l == 0, cut_right = r == N - 1;
      const double tl = cut_left ? pts.theta(0) : crossing(l, l - 1);
      const double tr = cut_right ? pts.theta(N - 1) : crossing(r, r + 1);
      Feature f;
      f.peak = pass == 0;
      f.height = h;
      f.theta = std::max(pts.theta(k), std::max(0.5 * tr, 1e-3 * theta_max));
      double width = tr - tl;
      if (cut_left != cut_right) width = 2.0 * (cut_left ? tr - f.theta : f.theta - tl);
      f.eps = std::clamp(width / (2.0 * f.theta), 1e-5, 2.0);
      f.fraction = static_cast<double>(r - l + 1) / static_cast<double>(N);
      out.push_back(f);
    }
  }
  return out;
}

/// (alpha, beta) of the quadratic with natural frequency theta_n (rad/sample) and
/// damping zeta (the pole-zero mapping of s^2 + 2 zeta w s + w^2), clamped to the box.
void set_quadratic(VectorXd& x, Index i, double theta_n, double zeta, double delta) {
  const double q1 = std::max(2.0 * zeta * theta_n - 2.0 * delta, delta);
  const double q0 = std::max(theta_n * theta_n - 2.0 * delta * zeta * theta_n + delta * delta,
                             std::max(1e-6 * theta_n * theta_n, 1e-13));
  x(i) = std::clamp(std::log(q1), kLogMin, kAlphaMax);
  x(i + 1) = std::clamp(std::log(q0), kLogMin, kBetaMax);
}

/// A section with the shape of a feature: for a peak of height H = exp(h) and
/// relative half-width eps, poles with zeta_p = eps / sqrt(H) and zeros with
/// zeta_z = eps sqrt(H) (file comment); a valley with the two swapped.
void set_feature_section(VectorXd& x, int section, const Feature& f, double delta) {
  const double root_h = std::exp(0.5 * std::min(f.height, 20.0));
  const double zeta_narrow = std::clamp(f.eps / root_h, 1e-7, 4.0), zeta_wide = std::clamp(f.eps * root_h, 1e-7, 4.0);
  const Index i = 1 + 4 * section;
  set_quadratic(x, i, f.theta, f.peak ? zeta_wide : zeta_narrow, delta);
  set_quadratic(x, i + 2, f.theta, f.peak ? zeta_narrow : zeta_wide, delta);
}

/// A smooth section at theta: well-damped zeros and poles at one frequency (nearly
/// a constant; the fit shapes it).
void set_smooth_section(VectorXd& x, int section, double theta, double delta) {
  set_quadratic(x, 1 + 4 * section, theta, 0.6, delta);
  set_quadratic(x, 1 + 4 * section + 2, theta, 0.8, delta);
}

/// First-order zero and pole around theta (a lead when the bound rises).
void set_first_order(VectorXd& x, const Layout& layout, double theta, bool rising, double delta) {
  const double tz = rising ? theta / 2.0 : theta * 2.0, tp = rising ? theta * 2.0 : theta / 2.0;
  const Index i = layout.first_index();
  x(i) = std::clamp(std::log(std::max(tz - delta, delta)), kLogMin, kGammaMax);
  x(i + 1) = std::clamp(std::log(std::max(tp - delta, delta)), kLogMin, kGammaMax);
}

/// Sets log g so that the median of e is 0.
void center_gain(const Layout& layout, VectorXd& x, const Points& pts, double delta) {
  x(0) = 0.0;
  VectorXd lw;
  log_magnitude(layout, x, pts, delta, lw, nullptr);
  const VectorXd d = pts.log_bound - lw;
  x(0) = std::clamp(median(std::vector<double>(d.data(), d.data() + d.size())), -kLogGainMax, kLogGainMax);
}

struct Band {
  double theta_lo = 0, theta_hi = 0;
  bool rising = true;
  /// theta of smooth section i of m, log-spaced over the band.
  double smooth_theta(int i, int m) const {
    const double t = (i + 0.5) / m;
    return std::exp((1.0 - t) * std::log(theta_lo) + t * std::log(theta_hi));
  }
};

/// A start with the given features as sections, the remaining sections smooth.
VectorXd start_from(const Layout& layout, const std::vector<Feature>& chosen, const Band& band, const Points& pts,
                    double delta) {
  VectorXd x = VectorXd::Zero(layout.size());
  const int m = layout.quadratics - static_cast<int>(chosen.size());
  int s = 0;
  for (const Feature& f : chosen) set_feature_section(x, s++, f, delta);
  for (int i = 0; i < m; ++i) set_smooth_section(x, s++, band.smooth_theta(i, m), delta);
  if (layout.first) set_first_order(x, layout, band.smooth_theta(0, 1), band.rising, delta);
  center_gain(layout, x, pts, delta);
  return x;
}

/// (alpha, beta) of the quadratic with roots r1, r2 (a conjugate pair, or two real
/// roots), clamped into the box; roots the parametrisation cannot hold (negative
/// reals) are replaced by a pair of the same radius product.
void set_quadratic_roots(VectorXd& x, Index i, Complex r1, Complex r2, double delta) {
  const double limit = -1.5 * delta;  // log radius of the largest root a start uses
  double q1 = 0, q0 = 0;
  if (r1.imag() != 0.0 || r2.imag() != 0.0) {
    Complex lambda = std::log(r1.imag() >= 0.0 ? r1 : std::conj(r1));
    lambda = Complex(std::min(lambda.real(), limit), std::min(lambda.imag(), 0.98 * kTwoPi / 2.0)) + delta;
    q1 = -2.0 * lambda.real();
    q0 = std::norm(lambda);
  } else if (r1.real() > 0.0 && r2.real() > 0.0) {
    const double l1 = std::min(std::log(std::max(r1.real(), 1e-9)), limit) + delta;
    const double l2 = std::min(std::log(std::max(r2.real(), 1e-9)), limit) + delta;
    q1 = -(l1 + l2);
    q0 = l1 * l2;
  } else {
    const double radius = std::sqrt(std::max(std::abs(r1.real() * r2.real()), 1e-18));
    const double angle = (r1.real() <= 0.0 && r2.real() <= 0.0) ? 0.95 * kTwoPi / 2.0 : kTwoPi / 4.0;
    set_quadratic_roots(x, i, std::polar(radius, angle), std::polar(radius, -angle), delta);
    return;
  }
  x(i) = std::clamp(std::log(std::max(q1, 1e-300)), kLogMin, kAlphaMax);
  x(i + 1) = std::clamp(std::log(std::max(q0, 1e-300)), kLogMin, kBetaMax);
}

/// Roots (in z, inside the unit circle) of the factor N(z) of degree `degree` whose
/// |N(e^{j theta})|^2 is the polynomial with Chebyshev coefficients `coef` in
/// xi = (2 cos theta - (c_max + c_min)) / (c_max - c_min) (cos theta - 1 =
/// (xi (c_max - c_min) + (c_max - 1) + (c_min - 1)) / 2, kept apart for accuracy
/// near theta = 0): each root c_r gives the root a of z + 1/z = 2 c_r with |a| <= 1.
/// A degree lost to a vanishing leading coefficient puts roots at z ~ 0.
std::vector<Complex> z_roots(const VectorXd& coef, int degree, double c_max_m1, double c_min_m1) {
  // Chebyshev -> monomial coefficients (degree <= 6: exact enough).
  const int d = static_cast<int>(coef.size()) - 1;
  std::vector<VectorXd> T{VectorXd::Unit(d + 1, 0)};
  if (d >= 1) T.push_back(VectorXd::Unit(d + 1, 1));
  for (int k = 2; k <= d; ++k) {
    VectorXd t = -T[static_cast<std::size_t>(k - 2)];
    t.tail(d).noalias() += 2.0 * T[static_cast<std::size_t>(k - 1)].head(d);
    T.push_back(t);
  }
  VectorXd mono = VectorXd::Zero(d + 1);
  for (int k = 0; k <= d; ++k) mono += coef(k) * T[static_cast<std::size_t>(k)];
  int deg = d;
  const double scale = mono.cwiseAbs().maxCoeff();
  while (deg > 0 && std::abs(mono(deg)) <= 1e-10 * scale) --deg;
  std::vector<Complex> roots;
  if (deg > 0) {
    MatrixXd companion = MatrixXd::Zero(deg, deg);
    for (int k = 0; k < deg; ++k) companion(0, k) = -mono(deg - 1 - k) / mono(deg);
    for (int k = 1; k < deg; ++k) companion(k, k - 1) = 1.0;
    const Eigen::EigenSolver<MatrixXd> es(companion, false);
    if (es.info() == Eigen::Success) {
      const double half_range = 0.5 * (c_max_m1 - c_min_m1);
      for (Eigen::Index k = 0; k < deg; ++k) {
        const Complex xi = es.eigenvalues()(k);
        if (xi.imag() < 0.0) continue;  // the conjugate of a root already taken
        const Complex cm1 = xi * half_range + 0.5 * (c_max_m1 + c_min_m1);  // c - 1
        const Complex c = cm1 + 1.0;
        Complex a = c - std::sqrt(cm1 * (cm1 + 2.0));
        if (std::abs(a) > 1.0) a = 1.0 / a;
        if (xi.imag() > 0.0) {
          roots.push_back(a);
          roots.push_back(std::conj(a));
        } else {
          // A real c: outside [-1, 1] a real root; inside, a point of the unit
          // circle (|W|^2 changes sign there): taken as the real root c.
          roots.emplace_back(std::abs(a.imag()) > 0.0 ? c.real() : a.real(), 0.0);
        }
      }
    }
  }
  while (static_cast<int>(roots.size()) < degree) roots.emplace_back(1e-3, 0.0);
  roots.resize(static_cast<std::size_t>(degree));
  return roots;
}

/// Writes the roots (conjugate pairs adjacent, as z_roots returns them) into the
/// zero (part 0) or pole (part 1) slots of x: pairs first, then real roots in pairs,
/// a last real root into the first-order factor.
void set_roots(VectorXd& x, const Layout& layout, int part, std::vector<Complex> roots, double delta) {
  std::vector<std::pair<Complex, Complex>> quads;
  std::vector<double> reals;
  for (std::size_t k = 0; k < roots.size(); ++k) {
    if (roots[k].imag() != 0.0 && k + 1 < roots.size() && roots[k + 1] == std::conj(roots[k])) {
      quads.emplace_back(roots[k], roots[k + 1]);
      ++k;
    } else {
      reals.push_back(roots[k].real());
    }
  }
  std::sort(reals.begin(), reals.end(), std::greater<>());
  std::size_t r = 0;
  while (static_cast<int>(quads.size()) < layout.quadratics && r + 1 < reals.size()) {
    quads.emplace_back(reals[r], reals[r + 1]);
    r += 2;
  }
  // Surplus pairs (when a lost degree left too few reals for the first-order factor):
  // their real parts go there.
  while (static_cast<int>(quads.size()) > layout.quadratics) {
    reals.push_back(std::abs(quads.back().first));
    quads.pop_back();
  }
  while (static_cast<int>(quads.size()) < layout.quadratics) quads.emplace_back(1e-3, 1e-3);
  for (int q = 0; q < layout.quadratics; ++q)
    set_quadratic_roots(x, 1 + 4 * q + 2 * part, quads[static_cast<std::size_t>(q)].first,
                        quads[static_cast<std::size_t>(q)].second, delta);
  if (layout.first) {
    const double root = r < reals.size() ? reals[r] : 1e-3;
    const double lr = std::min(std::log(std::max(root, 1e-9)), -1.5 * delta);
    x(layout.first_index() + part) = std::clamp(std::log(-lr - delta), kLogMin, kGammaMax);
  }
}

/// Linear start (file comment): |W(e^{j theta})|^2 = P_N(c) / P_D(c), c = cos theta,
/// P_N, P_D polynomials of degree `order` in c (Chebyshev basis over the grid's
/// range of c), fitted by Sanathanan-Koerner iterations (C. K. Sanathanan and J.
/// Koerner, IEEE Trans. Autom. Control 8 (1963) 56-58): each a total least-squares
/// solution (smallest right singular vector) of P_N(c_k) - b_k^2 P_D(c_k) ~ 0,
/// weighted by 1 / sqrt|b_k^2 P_N P_D| of the previous iterate (so the residual is
/// rho - 1/rho in the ratio rho = |W| / b). The roots of P_N and P_D give the zeros
/// and poles (z + 1/z = 2 c, the root inside the circle).
bool linear_start(const Layout& layout, const Points& pts, double delta, VectorXd& x) {
  const int n = layout.order();
  const Index N = pts.size();
  if (N < 2 * n + 3) return false;
  VectorXd cm1(N);  // cos theta - 1, accurately
  for (Index k = 0; k < N; ++k) {
    const double s = std::sin(0.5 * pts.theta(k));
    cm1(k) = -2.0 * s * s;
  }
  const double hi = cm1.maxCoeff(), lo = cm1.minCoeff();
  if (!(hi - lo > 1e-12)) return false;
  MatrixXd T(N, n + 1);
  for (Index k = 0; k < N; ++k) {
    const double xi = (2.0 * cm1(k) - (hi + lo)) / (hi - lo);
    T(k, 0) = 1.0;
    if (n >= 1) T(k, 1) = xi;
    for (int j = 2; j <= n; ++j) T(k, j) = 2.0 * xi * T(k, j - 1) - T(k, j - 2);
  }
  // The bound squared, over its geometric mean (no overflow; the gain is set after).
  const VectorXd b2 = (2.0 * (pts.log_bound.array() - pts.log_bound.mean())).exp();
  VectorXd w = b2.cwiseInverse();
  VectorXd coef_n, coef_d;
  for (int it = 0; it < 8; ++it) {
    MatrixXd M(N, 2 * (n + 1));
    M.leftCols(n + 1) = w.asDiagonal() * T;
    const VectorXd wb = -w.cwiseProduct(b2);
    M.rightCols(n + 1) = wb.asDiagonal() * T;
    VectorXd s = M.colwise().norm().transpose();
    for (Index j = 0; j < s.size(); ++j) s(j) = s(j) > 0.0 ? 1.0 / s(j) : 1.0;
    M = M * s.asDiagonal();
    const Eigen::JacobiSVD<MatrixXd> svd(M, Eigen::ComputeThinV);
    const VectorXd v = s.cwiseProduct(svd.matrixV().col(M.cols() - 1));
    if (!v.allFinite()) return false;
    coef_n = v.head(n + 1);
    coef_d = v.tail(n + 1);
    const VectorXd Pn = T * coef_n, Pd = T * coef_d;
    const VectorXd prod = (b2.cwiseProduct(Pn).cwiseProduct(Pd)).cwiseAbs();
    const double floor = 1e-12 * std::max(prod.maxCoeff(), 1e-300);
    for (Index k = 0; k < N; ++k) w(k) = 1.0 / std::sqrt(std::max(prod(k), floor));
  }
  x = VectorXd::Zero(layout.size());
  set_roots(x, layout, 0, z_roots(coef_n, n, hi, lo), delta);
  set_roots(x, layout, 1, z_roots(coef_d, n, hi, lo), delta);
  center_gain(layout, x, pts, delta);
  return x.allFinite();
}

/// The best fit of order - 1 extended by neutral roots (zero = pole, so the same
/// |W|): for an odd order a first-order factor (r, r); for an even one the
/// first-order roots (z_0, p_0) join r in a quadratic, zeros (z_0, r), poles (p_0, r).
VectorXd extend_neutral(const Fit& prev, const Layout& target, double r, double delta) {
  VectorXd x = VectorXd::Zero(target.size());
  x.head(1 + 4 * prev.layout.quadratics) = prev.x.head(1 + 4 * prev.layout.quadratics);
  const double lr = std::min(std::log(r), -1.5 * delta);
  if (target.first) {
    x.tail(2).setConstant(std::clamp(std::log(-lr - delta), kLogMin, kGammaMax));
  } else {
    const Index i = 1 + 4 * prev.layout.quadratics;
    for (int part = 0; part < 2; ++part) {
      const double root = first_order_root(prev.x(prev.layout.first_index() + part), delta);
      set_quadratic_roots(x, i + 2 * part, Complex(root, 0.0), Complex(r, 0.0), delta);
    }
  }
  return x;
}

/// The best fit of order - 2 with a section added at the largest feature of its
/// residual (the greedy step: a peak it leaves uncovered, or a valley where it
/// covers too much).
VectorXd extend_feature(const Fit& prev, const Layout& target, const Band& band, const Points& pts, double delta) {
  VectorXd lw;
  log_magnitude(prev.layout, prev.x, pts, delta, lw, nullptr);
  const VectorXd d = pts.log_bound - lw;
  // The fit covers, so d <= 0: humps are measured against its median.
  const VectorXd rel = d.array() - median(std::vector<double>(d.data(), d.data() + d.size()));
  Feature best;
  best.theta = band.smooth_theta(0, 1);
  best.height = 0.1;
  best.eps = 0.5;
  double best_score = -1.0;
  for (const Feature& f : features_of(pts, rel, 0.05)) {
    // Peaks decide the cover; valleys count by the points they span.
    const double score = f.height * (f.peak ? 1.0 : std::sqrt(f.fraction));
    if (score > best_score) {
      best_score = score;
      best = f;
    }
  }
  VectorXd x(target.size());
  x.head(1 + 4 * prev.layout.quadratics) = prev.x.head(1 + 4 * prev.layout.quadratics);
  if (target.first) x.tail(2) = prev.x.tail(2);
  set_feature_section(x, prev.layout.quadratics, best, delta);
  center_gain(target, x, pts, delta);
  return x;
}

/// What the search over the orders shares.
struct Search {
  const Points& pts;
  const UncertaintyWeightOptions& options;
  Band band;
  double delta = 0.0;
  std::vector<Feature> peaks;  ///< of the bound, highest first
  std::vector<Feature> all;    ///< peaks and valleys, most prominent first
  int iterations = 0;
  int starts = 0;
};

/// The best covering fit of one order: Levenberg-Marquardt from the independent
/// starts and from the extensions of the lower orders' best fits (prev1: order - 1,
/// prev2: order - 2; the neutral extension also as it is, so no order does worse
/// than the one below), then SQP refinement of the best `refine_starts`.
Fit best_of_order(Search& s, const Layout& layout, const Fit* prev1, const Fit* prev2) {
  std::vector<VectorXd> starts;
  auto add = [&](VectorXd x) {
    for (const VectorXd& y : starts)
      if ((y - x).norm() <= 1e-12 * (1.0 + x.norm())) return;
    starts.push_back(std::move(x));
  };
  {
    VectorXd x;
    if (linear_start(layout, s.pts, s.delta, x)) add(x);
  }
  const int Q = layout.quadratics;
  for (int k = std::min<int>(Q, static_cast<int>(s.peaks.size())); k >= 0; --k)
    add(start_from(layout, std::vector<Feature>(s.peaks.begin(), s.peaks.begin() + k), s.band, s.pts, s.delta));
  for (int k = 1; k <= std::min<int>(Q, static_cast<int>(s.all.size())); ++k)
    add(start_from(layout, std::vector<Feature>(s.all.begin(), s.all.begin() + k), s.band, s.pts, s.delta));
  // Each of the next peaks alone, the other sections smooth.
  for (std::size_t p = 1; Q >= 1 && p < std::min<std::size_t>(s.peaks.size(), 4); ++p)
    add(start_from(layout, {s.peaks[p]}, s.band, s.pts, s.delta));
  if (starts.size() > static_cast<std::size_t>(s.options.starts)) starts.resize(static_cast<std::size_t>(s.options.starts));

  std::vector<Fit> fits;
  Fit kept;  // the order below, extended as it is (refined already)
  if (prev1 && std::isfinite(prev1->score)) {
    const VectorXd x = extend_neutral(*prev1, layout, std::exp(-s.band.smooth_theta(0, 1)), s.delta);
    kept = covering_fit(layout, x, s.pts, s.delta, 0);
    starts.push_back(x);
  }
  if (prev2 && std::isfinite(prev2->score)) starts.push_back(extend_feature(*prev2, layout, s.band, s.pts, s.delta));
  for (const VectorXd& x0 : starts) {
    fits.push_back(lm_fit(layout, x0, s.pts, s.delta, s.options));
    s.iterations += fits.back().iterations;
    ++s.starts;
  }
  std::stable_sort(fits.begin(), fits.end(), [](const Fit& a, const Fit& b) { return a.score < b.score; });
  Fit best = kept.score < fits.front().score ? kept : fits.front();
  for (int i = 0; i < std::min<int>(s.options.refine_starts, static_cast<int>(fits.size())); ++i) {
    const Fit& start = fits[static_cast<std::size_t>(i)];
    if (!std::isfinite(start.score)) break;
    const Fit refined = sqp_refine(start, s.pts, s.delta, s.options.refine_evaluations);
    s.iterations += refined.iterations - start.iterations;
    if (refined.score < best.score) best = refined;
  }
  return best;
}

// ---------------------------------------------------------------------------
// Realisation: a cascade of sections (file comment, step 4).

struct Section {
  MatrixXd A, B, C;
  double D = 1.0;
};

/// Balances a section by a scalar state scaling: ||B|| = ||C||.
void balance(Section& s) {
  const double nb = s.B.norm(), nc = s.C.norm();
  if (nb > 0.0 && nc > 0.0) {
    const double sigma = std::sqrt(nc / nb);
    s.B *= sigma;
    s.C /= sigma;
  }
}

/// N / D = 1 + (c1 z + c0) / D(z) with A = [re, kappa; -disc / kappa, re].
Section quadratic_section(const Quadratic& num, const Quadratic& den) {
  const double c1 = num.a1 - den.a1, c0 = num.a2 - den.a2;
  const double kappa = std::max(std::sqrt(std::abs(den.disc)), 1e-3);
  Section s;
  s.A.resize(2, 2);
  s.A << den.re, kappa, -den.disc / kappa, den.re;
  s.B.resize(2, 1);
  s.B << 0.0, 1.0;
  s.C.resize(1, 2);
  s.C << (c0 + c1 * den.re) / kappa, c1;
  balance(s);
  return s;
}

StateSpace realise(const Layout& layout, const VectorXd& x, double delta, double Ts) {
  std::vector<Section> sections;
  for (int q = 0; q < layout.quadratics; ++q) {
    const Index i = 1 + 4 * q;
    sections.push_back(quadratic_section(quadratic(x(i), x(i + 1), delta), quadratic(x(i + 2), x(i + 3), delta)));
  }
  if (layout.first) {
    const double zr = first_order_root(x(layout.first_index()), delta);
    const double pr = first_order_root(x(layout.first_index() + 1), delta);
    Section s;
    s.A = MatrixXd::Constant(1, 1, pr);
    s.B = MatrixXd::Ones(1, 1);
    s.C = MatrixXd::Constant(1, 1, pr - zr);
    balance(s);
    sections.push_back(s);
  }
  // Series connection u -> S_1 -> S_2 -> ...: for G_2 G_1,
  // A = [A1 0; B2 C1 A2], B = [B1; B2 D1], C = [D2 C1, C2], D = D2 D1.
  MatrixXd A(0, 0), B(0, 1), C(1, 0);
  double D = 1.0;
  for (const Section& s : sections) {
    const Index n = A.rows(), k = s.A.rows();
    MatrixXd An = MatrixXd::Zero(n + k, n + k);
    An.topLeftCorner(n, n) = A;
    An.bottomLeftCorner(k, n) = s.B * C;
    An.bottomRightCorner(k, k) = s.A;
    MatrixXd Bn(n + k, 1);
    Bn.topRows(n) = B;
    Bn.bottomRows(k) = s.B * D;
    MatrixXd Cn(1, n + k);
    Cn.leftCols(n) = s.D * C;
    Cn.rightCols(k) = s.C;
    A = An;
    B = Bn;
    C = Cn;
    D *= s.D;
  }
  const double g = std::exp(x(0));
  return StateSpace(A, B, g * C, MatrixXd::Constant(1, 1, g * D), Ts);
}

std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  return buf;
}

}  // namespace

std::string UncertaintyWeightResult::brief_report() const {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "uncertainty weight: order %d, |W|/bound median %.3g, max %.3g at %.4g Hz, min %.6g; %d starts, %d "
                "iterations",
                static_cast<int>(weight.order()), median_conservatism, max_conservatism, max_conservatism_hz, min_ratio,
                starts, iterations);
  return buf;
}

UncertaintyWeightResult fit_uncertainty_weight(const Eigen::VectorXd& frequency_hz, const Eigen::VectorXd& bound,
                                               double Ts, const UncertaintyWeightOptions& options) {
  const std::string who = "fit_uncertainty_weight: ";
  if (!(Ts > 0.0) || !std::isfinite(Ts)) throw std::invalid_argument(who + "need Ts > 0 and finite");
  if (options.order < 1 || options.order > 6)
    throw std::invalid_argument(who + "need 1 <= order <= 6, got " + std::to_string(options.order));
  if (!(options.max_radius > 0.0 && options.max_radius < 1.0))
    throw std::invalid_argument(who + "need 0 < max_radius < 1");
  if (!(options.below_penalty >= 1.0) || !std::isfinite(options.below_penalty))
    throw std::invalid_argument(who + "need below_penalty >= 1 and finite");
  if (options.starts < 1 || options.max_iterations < 1 || options.refine_starts < 0 || options.refine_evaluations < 0)
    throw std::invalid_argument(who + "need starts >= 1, max_iterations >= 1, refine_starts >= 0, refine_evaluations >= 0");
  const Index M = frequency_hz.size();
  if (M < 1) throw std::invalid_argument(who + "need at least one frequency");
  if (bound.size() != M)
    throw std::invalid_argument(who + "frequency_hz and bound must have one size, are " + std::to_string(M) + " and " +
                                std::to_string(bound.size()));
  const double nyquist = 0.5 / Ts;
  for (Index k = 0; k < M; ++k) {
    const double f = frequency_hz(k);
    if (!std::isfinite(f)) throw std::invalid_argument(who + "frequency_hz[" + std::to_string(k) + "] is not finite");
    if (!(f >= 0.0 && f < nyquist))
      throw std::invalid_argument(who + format("need 0 <= frequency < Nyquist = 0.5 / Ts = %.6g Hz, frequency_hz[", nyquist) +
                                  std::to_string(k) + format("] = %.6g", f));
    if (k > 0 && !(f > frequency_hz(k - 1)))
      throw std::invalid_argument(who + "frequency_hz must be strictly increasing (at index " + std::to_string(k) + ")");
    if (!std::isfinite(bound(k))) throw std::invalid_argument(who + "bound[" + std::to_string(k) + "] is not finite");
    if (!(bound(k) >= 0.0))
      throw std::invalid_argument(who + "need bound >= 0, bound[" + std::to_string(k) + format("] = %.6g", bound(k)));
  }

  UncertaintyWeightResult res;
  // The points that carry a requirement.
  std::vector<Index> used;
  for (Index k = 0; k < M; ++k)
    if (bound(k) > 0.0) used.push_back(k);
  if (used.empty()) throw std::invalid_argument(who + "the bound is zero at every frequency: nothing to cover");
  const auto N = static_cast<Index>(used.size());
  if (N < M)
    res.warnings.push_back(std::to_string(M - N) + " of " + std::to_string(M) +
                           " frequencies have bound 0: no requirement there, and left out of the conservatism");
  Points pts;
  pts.theta.resize(N);
  pts.log_bound.resize(N);
  pts.logf.resize(N);
  for (Index i = 0; i < N; ++i) {
    pts.theta(i) = kTwoPi * frequency_hz(used[static_cast<std::size_t>(i)]) * Ts;
    pts.log_bound(i) = std::log(bound(used[static_cast<std::size_t>(i)]));
  }
  pts.cos = pts.theta.array().cos();
  pts.sin = pts.theta.array().sin();
  pts.cos2 = (2.0 * pts.theta.array()).cos();
  pts.sin2 = (2.0 * pts.theta.array()).sin();
  Band band;
  band.theta_hi = std::max(pts.theta(N - 1), 1e-6);
  {
    double first_positive = band.theta_hi;
    for (Index i = 0; i < N; ++i)
      if (pts.theta(i) > 0.0) {
        first_positive = pts.theta(i);
        break;
      }
    band.theta_lo = std::clamp(first_positive, 1e-4 * band.theta_hi, band.theta_hi);
    for (Index i = 0; i < N; ++i) pts.logf(i) = std::log(pts.theta(i) + 0.5 * band.theta_lo);
  }

  const Layout layout{options.order / 2, options.order % 2 == 1};
  if (N < layout.size())
    res.warnings.push_back("only " + std::to_string(N) + " frequencies with a bound > 0 for " +
                           std::to_string(layout.size()) + " weight parameters: the fit is not unique");
  const double delta = -std::log(options.max_radius);

  // Features of the bound against its running median over +-half an octave.
  const VectorXd baseline = running_median(pts, pts.log_bound, 0.5 * std::log(2.0));
  {
    const Index q = std::max<Index>(1, N / 10);
    band.rising = baseline.tail(q).mean() >= baseline.head(q).mean();
  }
  std::vector<Feature> all = features_of(pts, pts.log_bound - baseline, std::log(1.25));
  std::vector<Feature> peaks;
  for (const Feature& f : all)
    if (f.peak) peaks.push_back(f);
  std::stable_sort(peaks.begin(), peaks.end(), [](const Feature& a, const Feature& b) { return a.height > b.height; });
  // Mixed ranking: peaks by height (they decide the cover), valleys by depth and the
  // points they span (they decide the median).
  auto prominence = [](const Feature& f) { return f.peak ? f.height : f.height * std::min(1.0, 10.0 * f.fraction); };
  std::stable_sort(all.begin(), all.end(),
                   [&](const Feature& a, const Feature& b) { return prominence(a) > prominence(b); });

  // Orders 1, 2, ..., order in turn, each started also from the best fits below it.
  Search search{pts, options, band, delta, std::move(peaks), std::move(all)};
  std::vector<Fit> best_of(static_cast<std::size_t>(options.order) + 1);
  for (int ord = 1; ord <= options.order; ++ord) {
    const Layout lo{ord / 2, ord % 2 == 1};
    const auto u = static_cast<std::size_t>(ord);
    best_of[u] = best_of_order(search, lo, ord >= 2 ? &best_of[u - 1] : nullptr, ord >= 3 ? &best_of[u - 2] : nullptr);
  }
  const Fit& best = best_of.back();
  if (!std::isfinite(best.score)) throw NumericalError(who + "no start gave a finite fit");
  res.iterations = search.iterations;
  res.starts = search.starts;

  // Realise, evaluate |W| on the realisation and set the gain so the cover holds.
  res.weight = realise(best.layout, best.x, delta, Ts);
  const std::vector<Eigen::MatrixXcd> G = frequency_response(res.weight, frequency_hz);
  res.magnitude.resize(M);
  for (Index k = 0; k < M; ++k) res.magnitude(k) = std::abs(G[static_cast<std::size_t>(k)](0, 0));
  double need = 0.0;
  for (Index k : used) need = std::max(need, bound(k) / res.magnitude(k));
  if (!(need > 0.0) || !std::isfinite(need)) throw NumericalError(who + "the weight's gain is not finite on the grid");
  const double scale = need * (1.0 + 1e-12);
  res.weight.C *= scale;
  res.weight.D *= scale;
  res.magnitude *= scale;

  std::vector<double> ratios;
  ratios.reserve(used.size());
  res.min_ratio = std::numeric_limits<double>::infinity();
  for (Index k : used) {
    const double r = res.magnitude(k) / bound(k);
    ratios.push_back(r);
    res.min_ratio = std::min(res.min_ratio, r);
    if (r > res.max_conservatism) {
      res.max_conservatism = r;
      res.max_conservatism_hz = frequency_hz(k);
    }
  }
  res.median_conservatism = median(ratios);

  // Over-cover at a few points (the bound's notches) is harmless; over most of the
  // grid it costs the robust design performance.
  if (res.median_conservatism > 2.0)
    res.warnings.push_back(format("the weight exceeds the bound by a median factor %.3g (max %.3g at %.4g Hz)",
                                  res.median_conservatism, res.max_conservatism, res.max_conservatism_hz) +
                           (options.order < 6 ? ": a higher order follows the bound more closely" : ""));
  // Roots at the radius limit: the bound has a peak or notch narrower than
  // max_radius lets the weight follow.
  {
    double rmax = 0.0;
    for (int q = 0; q < best.layout.quadratics; ++q)
      for (int part = 0; part < 2; ++part) {
        const Index i = 1 + 4 * q + 2 * part;
        const Quadratic qd = quadratic(best.x(i), best.x(i + 1), delta);
        rmax = std::max(rmax, qd.disc >= 0.0 ? std::sqrt(qd.a2) : std::abs(qd.re) + std::sqrt(-qd.disc));
      }
    if (best.layout.first)
      for (int part = 0; part < 2; ++part)
        rmax = std::max(rmax, first_order_root(best.x(best.layout.first_index() + part), delta));
    if (rmax >= options.max_radius * (1.0 - 1e-9))
      res.warnings.push_back(format("a pole or zero of the weight is at the radius limit max_radius = %.6g: the bound "
                                    "has a peak or notch sharper than the weight may follow",
                                    options.max_radius));
  }
  // |W| between and beyond the listed frequencies: the cover holds on the grid only,
  // so a weight that peaks off it is pointed out (a grid too coarse for a
  // resonance of W, or a rise outside the band).
  {
    const Index n_lin = 2048, n_log = 1024;
    VectorXd dense(n_lin + n_log);
    dense.head(n_lin) = VectorXd::LinSpaced(n_lin, 0.0, nyquist * (1.0 - 1.0 / n_lin));
    const double f_lo = std::max(frequency_hz(0), 1e-4 * nyquist), f_hi = std::max(frequency_hz(M - 1), f_lo);
    for (Index i = 0; i < n_log; ++i)
      dense(n_lin + i) = f_lo * std::pow(f_hi / f_lo, static_cast<double>(i) / static_cast<double>(n_log - 1));
    const std::vector<Eigen::MatrixXcd> Gd = frequency_response(res.weight, dense);
    double peak = 0.0, peak_hz = 0.0;
    for (Index i = 0; i < dense.size(); ++i) {
      const double m = std::abs(Gd[static_cast<std::size_t>(i)](0, 0));
      if (m > peak) {
        peak = m;
        peak_hz = dense(i);
      }
    }
    const double grid_peak = res.magnitude.maxCoeff();
    if (peak > 2.0 * grid_peak)
      res.warnings.push_back(format("off the listed frequencies |W| reaches %.3g at %.4g Hz, ", peak, peak_hz) +
                             format("%.3g times its largest value on the grid: the grid misses a resonance of the "
                                    "weight there, or the weight rises outside the band",
                                    peak / grid_peak));
  }
  return res;
}

}  // namespace sysid
