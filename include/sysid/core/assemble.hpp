#pragma once
/// @file
/// Purpose: assemble models identified one excitation at a time (single input,
/// all outputs: SIMO) into one MIMO model, as the isolator workflow does after
/// exciting each actuator alone (realise each, then stack).
///
///   A = blkdiag(A_1..A_k),  B = blkdiag(B_1..B_k),  C = [C_1 .. C_k],  D = [D_1 .. D_k]
///
/// The outputs are shared (each part's response adds at the sensors), the inputs
/// are side by side; the order is the sum of the parts' orders. The frequency
/// response of the result is the parts' responses placed column by column,
/// exactly (superposition). Each part may have several inputs; they keep their
/// order. The result is generally not minimal (every part carries its own copy
/// of the structure's modes): reduce it (reduce/balanced_truncation.hpp).
///
/// Preconditions (std::invalid_argument, naming the part): at least one part;
/// the same sample time; the same number of outputs and, where named, the same
/// output names in the same order; no input name used twice.
#include <sysid/core/state_space.hpp>

#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

inline StateSpace assemble_inputs(const std::vector<StateSpace>& parts) {
  if (parts.empty()) throw std::invalid_argument("assemble: no models");
  const StateSpace& first = parts.front();
  Eigen::Index n = 0, m = 0;
  std::set<std::string> input_names;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const StateSpace& p = parts[k];
    const std::string which = "assemble: model " + std::to_string(k + 1);
    if (p.Ts != first.Ts)
      throw std::invalid_argument(which + " has Ts = " + std::to_string(p.Ts) + ", model 1 has " + std::to_string(first.Ts));
    if (p.outputs() != first.outputs())
      throw std::invalid_argument(which + " has " + std::to_string(p.outputs()) + " outputs, model 1 has " + std::to_string(first.outputs()));
    for (Eigen::Index i = 0; i < p.outputs(); ++i)
      if (p.output_name(i) != first.output_name(i))
        throw std::invalid_argument(which + ": output " + std::to_string(i + 1) + " is '" + p.output_name(i) + "', model 1 has '" +
                                    first.output_name(i) + "' (the outputs must be the same sensors in the same order)");
    for (Eigen::Index j = 0; j < p.inputs(); ++j)
      if (!input_names.insert(p.input_name(j)).second)
        throw std::invalid_argument(which + ": input '" + p.input_name(j) + "' appears in two models (name each experiment's input apart)");
    n += p.order();
    m += p.inputs();
  }
  const Eigen::Index l = first.outputs();
  StateSpace out;
  out.Ts = first.Ts;
  out.A = Eigen::MatrixXd::Zero(n, n);
  out.B = Eigen::MatrixXd::Zero(n, m);
  out.C = Eigen::MatrixXd::Zero(l, n);
  out.D = Eigen::MatrixXd::Zero(l, m);
  Eigen::Index xn = 0, um = 0;
  for (const StateSpace& p : parts) {
    out.A.block(xn, xn, p.order(), p.order()) = p.A;
    out.B.block(xn, um, p.order(), p.inputs()) = p.B;
    out.C.middleCols(xn, p.order()) = p.C;
    out.D.middleCols(um, p.inputs()) = p.D;
    for (Eigen::Index j = 0; j < p.inputs(); ++j) out.input_names.push_back(p.input_name(j));
    xn += p.order();
    um += p.inputs();
  }
  for (Eigen::Index i = 0; i < l; ++i) out.output_names.push_back(first.output_name(i));
  out.validate();
  return out;
}

}  // namespace sysid
