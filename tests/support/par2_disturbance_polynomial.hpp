#pragma once
// The denominator of the Par2 disturbance model GW(z) (the Par2 paper, eq. 5, at
// 2 kHz): two lightly damped resonances, about 25.9 Hz and 31.9 Hz, as the product
// of its quadratic factors (1 + b1 q^-1 + b0 q^-2)(1 + c1 q^-1 + c0 q^-2). The
// AR(4) process the time-series tests see through sensor noise.
#include <Eigen/Dense>

namespace sysid::test {

inline Eigen::VectorXd par2_disturbance_denominator() {
  const double b1 = -1.992, b0 = 0.9986, c1 = -1.963, c0 = 0.9729;
  Eigen::VectorXd a(5);
  a << 1.0, b1 + c1, b0 + b1 * c1 + c0, b1 * c0 + b0 * c1, b0 * c0;
  return a;
}

}  // namespace sysid::test
