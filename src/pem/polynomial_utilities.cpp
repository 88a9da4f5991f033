// The polynomial utilities of pem/prediction_error.hpp: the structure's name,
// the parameter vector of a polynomial model (pack/unpack), roots, reflection
// into the unit circle and the stability tests of the denominators.
#include <sysid/core/transfer_function.hpp>
#include <sysid/pem/prediction_error.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "pem/detail/polynomial_utilities.hpp"

namespace sysid {

std::string structure_name(int na, const std::vector<int>& nb, int nc, int nd, const std::vector<int>& nf) {
  const bool inputs = std::any_of(nb.begin(), nb.end(), [](int k) { return k > 0; });
  const bool f = std::any_of(nf.begin(), nf.end(), [](int k) { return k > 0; });
  if (!inputs) return nc > 0 ? (nd > 0 ? "polynomial" : "arma") : (nd > 0 ? "polynomial" : "ar");
  if (f) return na == 0 && nc == 0 && nd == 0 ? "oe" : (na == 0 ? "bj" : "polynomial");
  if (nd > 0) return "polynomial";
  return nc > 0 ? "armax" : "arx";
}

Eigen::VectorXd pack_parameters(const PolynomialModel& model) {
  Eigen::Index p = model.na() + model.nc() + model.nd();
  for (Eigen::Index i = 0; i < model.inputs(); ++i) p += model.nb(i) + model.nf(i);
  Eigen::VectorXd theta(p);
  Eigen::Index at = 0;
  auto put = [&](const Eigen::VectorXd& v) {
    theta.segment(at, v.size()) = v;
    at += v.size();
  };
  put(model.A.tail(model.na()));
  for (const auto& b : model.B) put(b);
  put(model.C.tail(model.nc()));
  put(model.D.tail(model.nd()));
  for (const auto& f : model.F) put(f.tail(f.size() - 1));
  return theta;
}

void unpack_parameters(const Eigen::VectorXd& theta, PolynomialModel& model) {
  if (theta.size() != pack_parameters(model).size()) throw std::invalid_argument("pem: parameter vector of the wrong size");
  Eigen::Index at = 0;
  auto take = [&](Eigen::VectorXd& v, Eigen::Index first) {
    v.segment(first, v.size() - first) = theta.segment(at, v.size() - first);
    at += v.size() - first;
  };
  take(model.A, 1);
  for (auto& b : model.B) take(b, 0);
  take(model.C, 1);
  take(model.D, 1);
  for (auto& f : model.F) take(f, 1);
}

Eigen::VectorXcd polynomial_roots(const Eigen::VectorXd& monic) {
  const Eigen::Index n = monic.size() - 1;
  if (n <= 0) return Eigen::VectorXcd();
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  companion.row(0) = -monic.tail(n).transpose();
  if (n > 1) companion.bottomLeftCorner(n - 1, n - 1).setIdentity();
  return companion.eigenvalues();
}

Eigen::VectorXd reflect_into_unit_circle(const Eigen::VectorXd& monic) {
  Eigen::VectorXcd roots = polynomial_roots(monic);
  bool changed = false;
  for (auto& z : roots)
    if (std::abs(z) >= 1.0) {
      z = 1.0 / std::conj(z) * (std::abs(z) == 1.0 ? 0.999 : 1.0);  // a root on the circle is pulled just inside
      changed = true;
    }
  if (!changed) return monic;
  return poly_from_roots(roots);  // reflection keeps conjugate pairs: the result is real
}

namespace detail::pem_impl {

bool strictly_stable(const Eigen::VectorXd& monic) {
  if (monic.size() <= 1) return true;
  const Eigen::VectorXcd r = polynomial_roots(monic);
  return r.cwiseAbs().maxCoeff() < 1.0 - 1e-10;
}

bool denominators_stable(const PolynomialModel& m) {
  if (!strictly_stable(m.C) || !strictly_stable(m.D)) return false;
  for (const auto& f : m.F)
    if (!strictly_stable(f)) return false;
  return true;
}

}  // namespace detail::pem_impl

}  // namespace sysid
