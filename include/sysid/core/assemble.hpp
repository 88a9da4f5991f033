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

#include <Eigen/Cholesky>

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

/// Purpose: a time-series model in innovation form (x+ = A x + K e, y = C x + e,
/// Cov e = Lambda: an AR/ARMA model, or n4sid on a record without inputs) as a
/// model whose inputs w are unit-variance white noise: (A, K L, C, L), L the lower
/// Cholesky factor of Lambda, so y = C (zI - A)^-1 K L w + L w with Cov w = I. Its
/// inputs are named w_<output>. Stacked beside a plant by assemble_inputs it gives
/// the generalised plant y = G u + H w of the Par2 paper's Fig. 4, the form an H2
/// or H-infinity synthesis takes.
/// Preconditions (std::invalid_argument): a model without inputs; K is n x l and
/// Lambda l x l, symmetric positive definite.
inline StateSpace disturbance_input_model(const StateSpace& model, const Eigen::MatrixXd& K, const Eigen::MatrixXd& noise_covariance) {
  const Eigen::Index n = model.order(), l = model.outputs();
  if (model.inputs() > 0)
    throw std::invalid_argument("disturbance model: needs a time-series model (no inputs: AR, ARMA, n4sid without inputs); "
                                "this one has " + std::to_string(model.inputs()) + " input(s)");
  if (K.rows() != n || K.cols() != l)
    throw std::invalid_argument("disturbance model: needs its Kalman gain K (" + std::to_string(n) + " x " + std::to_string(l) +
                                "): an AR, ARMA or time-series model");
  if (noise_covariance.rows() != l || noise_covariance.cols() != l)
    throw std::invalid_argument("disturbance model: needs its innovation covariance (" + std::to_string(l) + " x " +
                                std::to_string(l) + ")");
  const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (noise_covariance + noise_covariance.transpose()));
  if (llt.info() != Eigen::Success)
    throw std::invalid_argument("disturbance model: the innovation covariance is not positive definite");
  const Eigen::MatrixXd L = llt.matrixL();
  StateSpace out(model.A, K * L, model.C, L, model.Ts);
  out.output_names = model.output_names_or_defaults();
  for (Eigen::Index i = 0; i < l; ++i) out.input_names.push_back("w_" + out.output_names[static_cast<std::size_t>(i)]);
  return out;
}

}  // namespace sysid
