// Implementation of core/transfer_function.hpp (method and references in the header).
#include "core/detail/poles_zeros.hpp"
#include <sysid/core/format_number.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/transfer_function.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

namespace {

/// Drops exact leading zeros (they do not change the polynomial's degree meaning).
Eigen::VectorXd strip_leading_zeros(const Eigen::VectorXd& p) {
  Eigen::Index i = 0;
  while (i < p.size() && p[i] == 0.0) ++i;
  return p.tail(p.size() - i);
}

/// Double-double arithmetic (an unevaluated sum hi + lo, ~106-bit significand)
/// from error-free transformations: TwoSum (Knuth) and TwoProduct via fma
/// (Dekker; Ogita, Rump & Oishi 2005). Used only for the Taylor shift below, where
/// the cancellation that clustered roots cause would otherwise eat the digits.
struct DoubleDouble {
  double hi = 0.0, lo = 0.0;
};

DoubleDouble dd_add(DoubleDouble a, DoubleDouble b) {
  const double s = a.hi + b.hi;
  const double bb = s - a.hi;
  const double e = (a.hi - (s - bb)) + (b.hi - bb) + a.lo + b.lo;
  const double hi = s + e;
  return {hi, e - (hi - s)};
}

DoubleDouble dd_mul(DoubleDouble a, double b) {
  const double p = a.hi * b;
  const double e = std::fma(a.hi, b, -p) + a.lo * b;
  const double hi = p + e;
  return {hi, e - (hi - p)};
}

/// Coefficients (descending) of q(w) = p(w + shift), by repeated synthetic
/// division (Horner's Taylor-shift scheme, O(n^2)) in double-double, rounded
/// once at the end: the result is correctly rounded up to a few ulps even when
/// the shifted coefficients are tiny differences of large binomial sums.
Eigen::VectorXd taylor_shift(const Eigen::VectorXd& p, double shift) {
  const Eigen::Index n = p.size() - 1;
  std::vector<DoubleDouble> c(static_cast<std::size_t>(p.size()));
  for (Eigen::Index i = 0; i <= n; ++i) c[static_cast<std::size_t>(i)] = {p[i], 0.0};
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 1; j <= n - i; ++j) {
      const auto uj = static_cast<std::size_t>(j);
      c[uj] = dd_add(c[uj], dd_mul(c[uj - 1], shift));
    }
  Eigen::VectorXd q(p.size());
  for (Eigen::Index i = 0; i <= n; ++i) q[i] = c[static_cast<std::size_t>(i)].hi + c[static_cast<std::size_t>(i)].lo;
  return q;
}

/// One printed factor: a real root (x - r) or a conjugate pair (x^2 + a x + b),
/// with multiplicity.
struct PolyFactor {
  bool quadratic = false;
  double r = 0.0;           ///< real root (linear factor)
  double a = 0.0, b = 0.0;  ///< x^2 + a x + b
  std::complex<double> root;  ///< representative root (Im >= 0), for ordering and clustering
  int power = 1;
};

/// Groups roots into real and quadratic factors. A conjugate pair whose imaginary
/// part does not show at `digits` significant digits in b = |p|^2 becomes a
/// double real root, and roots closer than 10^-digits (relative) are clustered
/// into one factor with a power, so rounding-split multiple roots print as (x+1)^2.
std::vector<PolyFactor> factorise(const Eigen::VectorXcd& roots, int digits) {
  const double resolution = std::pow(10.0, -digits);
  std::vector<double> reals;
  std::vector<std::complex<double>> pairs;
  for (Eigen::Index i = 0; i < roots.size(); ++i) {
    const std::complex<double> p = roots[i];
    if (p.imag() < 0.0) continue;  // its conjugate stands for it
    if (p.imag() == 0.0) {
      reals.push_back(p.real());
    } else if (p.imag() * p.imag() <= 0.5 * resolution * std::norm(p)) {
      reals.push_back(p.real());
      reals.push_back(p.real());
    } else {
      pairs.push_back(p);
    }
  }
  std::vector<PolyFactor> out;
  std::sort(reals.begin(), reals.end());
  for (std::size_t i = 0; i < reals.size();) {
    std::size_t j = i + 1;
    double sum = reals[i];
    while (j < reals.size() && reals[j] - reals[j - 1] <= resolution * std::max(1.0, std::abs(reals[j]))) sum += reals[j++];
    PolyFactor f;
    f.r = sum / static_cast<double>(j - i);
    f.root = f.r;
    f.power = static_cast<int>(j - i);
    out.push_back(f);
    i = j;
  }
  std::vector<bool> used(pairs.size(), false);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (used[i]) continue;
    std::complex<double> sum = pairs[i];
    int count = 1;
    for (std::size_t j = i + 1; j < pairs.size(); ++j) {
      if (!used[j] && std::abs(pairs[j] - pairs[i]) <= resolution * std::max(1.0, std::abs(pairs[i]))) {
        used[j] = true;
        sum += pairs[j];
        ++count;
      }
    }
    PolyFactor f;
    f.quadratic = true;
    f.root = sum / static_cast<double>(count);
    f.a = -2.0 * f.root.real();
    f.b = std::norm(f.root);
    f.power = count;
    out.push_back(f);
  }
  return out;
}

std::string format_factors(std::vector<PolyFactor> factors, char var, bool discrete, int digits) {
  // Discrete: by angle of the root (0 .. pi, i.e. by frequency), then modulus;
  // continuous: by modulus (natural frequency), then angle.
  std::sort(factors.begin(), factors.end(), [discrete](const PolyFactor& f, const PolyFactor& g) {
    const double af = std::arg(f.root), ag = std::arg(g.root), mf = std::abs(f.root), mg = std::abs(g.root);
    if (discrete) return af != ag ? af < ag : mf < mg;
    return mf != mg ? mf < mg : af < ag;
  });
  const std::string x(1, var);
  std::string s;
  for (const PolyFactor& f : factors) {
    std::string body;
    bool bare = false;  // a plain power of x needs no parentheses
    if (!f.quadratic) {
      const std::string r = format_number(std::abs(f.r), digits);
      if (r == "0") {
        body = x;
        bare = true;
      } else {
        body = x + (f.r > 0.0 ? "-" : "+") + r;
      }
    } else {
      body = x + "^2";
      const std::string a = format_number(std::abs(f.a), digits);
      if (a != "0") body += (f.a < 0.0 ? "-" : "+") + (a == "1" ? std::string() : a) + x;
      body += "+" + format_number(f.b, digits);
    }
    s += bare ? body : "(" + body + ")";
    if (f.power > 1) s += "^" + std::to_string(f.power);
  }
  return s;
}

}  // namespace

Eigen::VectorXd poly_from_roots(const Eigen::VectorXcd& roots) {
  const Eigen::Index r = roots.size();
  Eigen::VectorXcd c = Eigen::VectorXcd::Zero(r + 1);
  c[0] = 1.0;
  for (Eigen::Index k = 0; k < r; ++k) {
    // multiply by (x - root_k): new c[i] = c[i] - root_k c[i-1], in place from the back
    for (Eigen::Index i = k + 1; i >= 1; --i) c[i] -= roots[k] * c[i - 1];
  }
  const double scale = c.cwiseAbs().maxCoeff();
  if (c.imag().cwiseAbs().maxCoeff() > 1e-8 * scale)
    throw std::invalid_argument("poly_from_roots: complex roots must come in conjugate pairs");
  return c.real();
}

Eigen::VectorXd poly_multiply(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() == 0 || b.size() == 0) return Eigen::VectorXd();
  Eigen::VectorXd c = Eigen::VectorXd::Zero(a.size() + b.size() - 1);
  for (Eigen::Index i = 0; i < a.size(); ++i) c.segment(i, b.size()) += a[i] * b;
  return c;
}

StateSpace to_state_space(const TransferFunction& tf) {
  if (!tf.num.allFinite() || !tf.den.allFinite()) throw std::invalid_argument("to_state_space: coefficients must be finite");
  if (!(tf.Ts >= 0.0) || !std::isfinite(tf.Ts)) throw std::invalid_argument("to_state_space: need Ts >= 0");
  const Eigen::VectorXd den = strip_leading_zeros(tf.den);
  const Eigen::VectorXd num = strip_leading_zeros(tf.num);
  if (den.size() == 0) throw std::invalid_argument("to_state_space: denominator is zero");
  const Eigen::Index n = den.size() - 1;
  if (num.size() > den.size())
    throw std::invalid_argument("to_state_space: need deg num <= deg den (" + std::to_string(num.size() - 1) + " > " +
                                std::to_string(n) + ")");
  const Eigen::VectorXd a = den / den[0];
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 1);
  b.tail(num.size()) = num / den[0];
  const double sigma = (tf.Ts > 0.0 && n > 0) ? -a[1] / static_cast<double>(n) : 0.0;
  const Eigen::VectorXd c = sigma != 0.0 ? taylor_shift(a, sigma) : a;
  const Eigen::VectorXd d = sigma != 0.0 ? taylor_shift(b, sigma) : b;
  Eigen::MatrixXd A = sigma * Eigen::MatrixXd::Identity(n, n), B(n, 1), C = Eigen::MatrixXd::Zero(1, n), D(1, 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (i + 1 < n) A(i + 1, i) = 1.0;
    A(i, n - 1) -= c[n - i];
    // d_i - c_i d_0 with one rounding (fma), the numerator of the strictly proper part
    B(i, 0) = std::fma(-c[n - i], d[0], d[n - i]);
  }
  if (n > 0) C(0, n - 1) = 1.0;
  D(0, 0) = d[0];
  return StateSpace(std::move(A), std::move(B), std::move(C), std::move(D), tf.Ts);
}

ZeroPoleGain zero_pole_gain(const StateSpace& sys, Eigen::Index output, Eigen::Index input) {
  sys.validate();
  if (output < 0 || output >= sys.outputs() || input < 0 || input >= sys.inputs())
    throw std::invalid_argument("zero_pole_gain: need 0 <= output < " + std::to_string(sys.outputs()) +
                                " and 0 <= input < " + std::to_string(sys.inputs()));
  ZeroPoleGain zpk;
  zpk.Ts = sys.Ts;
  zpk.poles = poles(sys);
  const detail::InvariantZeros iz =
      detail::invariant_zeros(sys.A, sys.B.col(input), sys.C.row(output), sys.D.block(output, input, 1, 1));
  if (iz.normal_rank == 0) {
    zpk.gain = 0.0;
    return zpk;
  }
  zpk.zeros = iz.zeros;
  double rmax = 1.0;
  for (Eigen::Index i = 0; i < zpk.zeros.size(); ++i) rmax = std::max(rmax, std::abs(zpk.zeros[i]));
  for (Eigen::Index i = 0; i < zpk.poles.size(); ++i) rmax = std::max(rmax, std::abs(zpk.poles[i]));
  const std::complex<double> x0 = std::polar(2.0 * rmax, 1.1);
  const StateSpace channel(sys.A, sys.B.col(input), sys.C.row(output), sys.D.block(output, input, 1, 1), sys.Ts);
  std::complex<double> k = frequency_response_at(channel, x0)(0, 0);
  const Eigen::Index nz = zpk.zeros.size(), np = zpk.poles.size();
  for (Eigen::Index i = 0; i < std::max(nz, np); ++i) {
    if (i < np) k *= x0 - zpk.poles[i];
    if (i < nz) k /= x0 - zpk.zeros[i];
  }
  zpk.gain = k.real();
  return zpk;
}

std::string format_factored(const ZeroPoleGain& zpk, int digits) {
  if (digits < 1) throw std::invalid_argument("format_factored: need digits >= 1");
  const bool discrete = zpk.Ts > 0.0;
  const char var = discrete ? 'z' : 's';
  std::string s = format_number(zpk.gain, digits);
  const std::string num = format_factors(factorise(zpk.zeros, digits), var, discrete, digits);
  const std::string den = format_factors(factorise(zpk.poles, digits), var, discrete, digits);
  if (!num.empty()) s += " " + num;
  if (!den.empty()) s += " / [" + den + "]";
  return s;
}

}  // namespace sysid
