// ARX with na = nb = 32 on 10^6 samples (issue 4: target under 2 s), SISO, by the
// library's route (pem/arx.hpp: the double-double Gram matrix of the lagged
// regressors from lagged sums, pem/lagged_regression.hpp). For scale,
// the same run times the cheapest conceivable estimator on the same data: the
// normal equations X^T X theta = X^T y by one Cholesky (which the library avoids
// for accuracy, STYLE.md), and reports the ratio. The data are a 4th-order
// lightly damped plant with white input and 1 % white equation noise, so the
// estimate can be checked: the residual variance must equal the noise variance
// to 1 %. Exit 1 when the target or the check fails.
#include <sysid/pem/arx.hpp>

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main() {
  constexpr Eigen::Index kSamples = 1000000;
  constexpr int kOrder = 32;
  constexpr double kNoise = 0.01;
  // A(q) = (1 - 1.94 q^-1 + 0.98 q^-2)(1 - 1.6 q^-1 + 0.9 q^-2), B = 0.05 q^-1 + 0.03 q^-2.
  const Eigen::Vector4d a(-1.94 - 1.6, 0.98 + 0.9 + 1.94 * 1.6, -(1.94 * 0.9 + 0.98 * 1.6), 0.98 * 0.9);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd u(kSamples, 1), y(kSamples, 1);
  for (Eigen::Index t = 0; t < kSamples; ++t) {
    u(t, 0) = g(rng);
    double v = kNoise * g(rng);
    for (int k = 1; k <= 4 && t - k >= 0; ++k) v -= a(k - 1) * y(t - k, 0);
    if (t >= 1) v += 0.05 * u(t - 1, 0);
    if (t >= 2) v += 0.03 * u(t - 2, 0);
    y(t, 0) = v;
  }
  sysid::ArxOptions o;
  o.na = kOrder;
  o.nb = {kOrder};
  o.nk = {1};
  const sysid::IoData data(u, y, 1e-3);

  auto t0 = std::chrono::steady_clock::now();
  const sysid::LinearPolynomialResult r = sysid::arx(data, o);
  const double library_s = seconds_since(t0);

  // Reference: normal equations on the same regressors (rows where every lag exists).
  t0 = std::chrono::steady_clock::now();
  const Eigen::Index rows = kSamples - kOrder, p = 2 * kOrder;
  Eigen::MatrixXd X(rows, p);
  for (int k = 1; k <= kOrder; ++k) {
    X.col(k - 1) = -y.col(0).segment(kOrder - k, rows);
    X.col(kOrder + k - 1) = u.col(0).segment(kOrder - k, rows);
  }
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(p, p);
  gram.selfadjointView<Eigen::Lower>().rankUpdate(X.transpose());
  const Eigen::VectorXd theta = gram.selfadjointView<Eigen::Lower>().llt().solve(X.transpose() * y.col(0).tail(rows));
  const double normal_s = seconds_since(t0);

  const double variance = r.models.front().noise_variance;
  const bool accurate = std::abs(variance / (kNoise * kNoise) - 1.0) < 0.01;
  const bool fast = library_s < 2.0;
  std::printf("ARX(%d, %d) on %ld samples: %.3f s (target < 2 s: %s); normal equations %.3f s (ratio %.2f)\n", kOrder,
              kOrder, static_cast<long>(kSamples), library_s, fast ? "met" : "NOT met", normal_s, library_s / normal_s);
  std::printf("residual variance / noise variance = %.5f (must be 1 within 1 %%: %s); condition %.3g; theta[0] %.6f vs %.6f\n",
              variance / (kNoise * kNoise), accurate ? "ok" : "FAILED", r.condition.front(), r.models.front().A(1),
              theta(0));
  return fast && accurate ? 0 : 1;
}
