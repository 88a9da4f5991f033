#pragma once
// Small FE structures shared by the fem tests and the FE benchmark.
#include <sysid/fem/beam_model.hpp>

#include <Eigen/Dense>
#include <complex>
#include <numbers>
#include <vector>

namespace sysid::test {

/// A steel-like beam (1 m, EI = 100 N m^2, rhoA = 2 kg/m) of `elements` elements on
/// two isolator springs (k = 2e4 N/m each, dampers when `dampers`), force at 0.3 L,
/// displacement, velocity and acceleration read at the tip and at mid-span.
inline fem::SecondOrderModel beam_on_isolators(int elements, bool dampers = false) {
  fem::BeamOptions o;
  o.elements = elements;
  o.flexural_rigidity = 100.0;
  o.mass_per_length = 2.0;
  fem::StructureBuilder b(o);
  const double c = dampers ? 8.0 : 0.0;
  b.add_spring_to_ground(b.translation_dof(b.node_at(0.1)), 2e4, c);
  b.add_spring_to_ground(b.translation_dof(b.node_at(0.9)), 2e4, c);
  const Eigen::Index force = b.translation_dof(b.node_at(0.3)), tip = b.translation_dof(elements),
                     mid = b.translation_dof(b.node_at(0.5));
  return b.finish({{"F", force, "N"}},
                  {{"x_tip", tip, fem::Quantity::displacement, "m"},
                   {"v_mid", mid, fem::Quantity::velocity, "m/s"},
                   {"a_tip", tip, fem::Quantity::acceleration, "m/s^2"}});
}

/// Every mode of a small model by the dense generalised eigensolver (the reference
/// the sparse paths are checked against): eigenvalues ascending, Phi^T M Phi = I.
struct DenseModes {
  Eigen::VectorXd eigenvalues;
  Eigen::MatrixXd shapes;
};
inline DenseModes dense_modes(const fem::SecondOrderModel& model) {
  const Eigen::MatrixXd k = Eigen::MatrixXd(model.stiffness), m = Eigen::MatrixXd(model.mass);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(k, m);
  return {solver.eigenvalues(), solver.eigenvectors()};
}

/// The dense direct solution H = S (K - w^2 M + j w C)^{-1} F at one frequency.
inline Eigen::MatrixXcd dense_response(const fem::SecondOrderModel& model, double f_hz) {
  using C = std::complex<double>;
  const double w = 2.0 * std::numbers::pi * f_hz;
  const Eigen::MatrixXcd z = Eigen::MatrixXd(model.stiffness).cast<C>() - w * w * Eigen::MatrixXd(model.mass).cast<C>() +
                             C(0.0, w) * Eigen::MatrixXd(model.effective_damping_matrix()).cast<C>();
  Eigen::MatrixXcd f = Eigen::MatrixXcd::Zero(model.dofs(), static_cast<Eigen::Index>(model.inputs.size()));
  for (std::size_t j = 0; j < model.inputs.size(); ++j) f(model.inputs[j].dof, static_cast<Eigen::Index>(j)) = 1.0;
  const Eigen::MatrixXcd x = z.partialPivLu().solve(f);
  Eigen::MatrixXcd h(static_cast<Eigen::Index>(model.outputs.size()), f.cols());
  for (std::size_t i = 0; i < model.outputs.size(); ++i) {
    const auto& out = model.outputs[i];
    const C factor = fem::quantity_factor(out.quantity, w);
    h.row(static_cast<Eigen::Index>(i)) = factor * x.row(out.dof);
  }
  return h;
}

}  // namespace sysid::test
