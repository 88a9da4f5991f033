// Implementation of core/modal_assurance_criterion.hpp.
#include <sysid/core/modal_assurance_criterion.hpp>

#include <complex>

namespace sysid {

double modal_assurance_criterion(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  if (a.size() != b.size() || a.size() == 0) return 0.0;
  const double na = a.squaredNorm(), nb = b.squaredNorm();
  if (!(na > 0.0 && nb > 0.0)) return 0.0;
  return std::norm(a.dot(b)) / (na * nb);  // a.dot(b) = a^H b
}

}  // namespace sysid
