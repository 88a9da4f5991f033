#pragma once
/// @file
/// Purpose: series connection and block-diagonal stacking of discrete or
/// continuous state-space models.
///
/// Method: for u -> first -> second -> y with states [x1; x2]:
///   A = [A1 0; B2 C1 A2], B = [B1; B2 D1], C = [D2 C1  C2], D = D2 D1.
/// Preconditions: equal sample times; second.inputs() == first.outputs()
/// (std::invalid_argument otherwise).
#include <sysid/core/state_space.hpp>

#include <stdexcept>
#include <vector>

namespace sysid {

inline StateSpace series(const StateSpace& first, const StateSpace& second) {
  if (first.Ts != second.Ts) throw std::invalid_argument("series: the models have different sample times");
  if (second.inputs() != first.outputs())
    throw std::invalid_argument("series: need second.inputs() == first.outputs() (" + std::to_string(second.inputs()) +
                                " != " + std::to_string(first.outputs()) + ")");
  const Eigen::Index n1 = first.order(), n2 = second.order();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n1 + n2, n1 + n2), b(n1 + n2, first.inputs()), c(second.outputs(), n1 + n2);
  a.topLeftCorner(n1, n1) = first.A;
  a.bottomLeftCorner(n2, n1) = second.B * first.C;
  a.bottomRightCorner(n2, n2) = second.A;
  b << first.B, second.B * first.D;
  c << second.D * first.C, second.C;
  StateSpace out(a, b, c, second.D * first.D, first.Ts);
  out.input_names = first.input_names;
  out.output_names = second.output_names;
  return out;
}

/// Block-diagonal stacking: inputs and outputs of the parts side by side.
inline StateSpace block_diagonal(const std::vector<StateSpace>& parts) {
  if (parts.empty()) throw std::invalid_argument("block_diagonal: no models");
  Eigen::Index n = 0, m = 0, l = 0;
  for (const auto& p : parts) {
    if (p.Ts != parts.front().Ts) throw std::invalid_argument("block_diagonal: the models have different sample times");
    n += p.order();
    m += p.inputs();
    l += p.outputs();
  }
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n), b = Eigen::MatrixXd::Zero(n, m), c = Eigen::MatrixXd::Zero(l, n),
                  d = Eigen::MatrixXd::Zero(l, m);
  Eigen::Index xn = 0, um = 0, yl = 0;
  for (const auto& p : parts) {
    a.block(xn, xn, p.order(), p.order()) = p.A;
    b.block(xn, um, p.order(), p.inputs()) = p.B;
    c.block(yl, xn, p.outputs(), p.order()) = p.C;
    d.block(yl, um, p.outputs(), p.inputs()) = p.D;
    xn += p.order();
    um += p.inputs();
    yl += p.outputs();
  }
  return StateSpace(a, b, c, d, parts.front().Ts);
}

}  // namespace sysid
