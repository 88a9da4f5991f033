#pragma once
// Small FE structures shared by the fem tests and the FE benchmark.
#include <sysid/fem/beam_model.hpp>

#include <Eigen/Dense>
#include <cmath>
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

/// A clamped-free axial rod (1 m, EA / rhoA = c^2 with c = 267 m/s, rhoA = 1 kg/m:
/// modes at (2 r - 1) c / 4 = 66.8, 200, 334, ... Hz, 15 below 2 kHz) of `elements`
/// linear elements with consistent mass, Rayleigh damping alpha = 2 /s, beta = 1e-6 s;
/// forces at the tip and at 0.4 L, displacement at the tip, velocity at 0.7 L.
/// Its eigenvalues span a ratio of only about (2 elements / pi)^2 (a beam's grows
/// as elements^4), so direct solves and the modal sum stay accurate at hundreds of
/// DOFs: the model to check large-model methods against them tightly.
inline fem::SecondOrderModel axial_rod(int elements) {
  const double h = 1.0 / elements, c = 267.0, rho_a = 1.0, ea = rho_a * c * c;
  std::vector<Eigen::Triplet<double>> kt, mt;
  for (int e = 0; e < elements; ++e) {
    // Element DOFs e - 1 and e (node 0 is clamped: DOF e is node e + 1).
    const int dofs[2] = {e - 1, e};
    const double ke[2][2] = {{1, -1}, {-1, 1}}, me[2][2] = {{2, 1}, {1, 2}};
    for (int p = 0; p < 2; ++p)
      for (int q = 0; q < 2; ++q) {
        if (dofs[p] < 0 || dofs[q] < 0) continue;
        kt.emplace_back(dofs[p], dofs[q], ea / h * ke[p][q]);
        mt.emplace_back(dofs[p], dofs[q], rho_a * h / 6.0 * me[p][q]);
      }
  }
  fem::SecondOrderModel m;
  m.stiffness.resize(elements, elements);
  m.mass.resize(elements, elements);
  m.stiffness.setFromTriplets(kt.begin(), kt.end());
  m.mass.setFromTriplets(mt.begin(), mt.end());
  m.damping.kind = fem::DampingKind::rayleigh;
  m.damping.alpha = 2.0;
  m.damping.beta = 1e-6;
  const auto at = [&](double x) { return static_cast<Eigen::Index>(std::lround(x * elements)) - 1; };
  m.inputs = {{"F_tip", at(1.0), "N"}, {"F_04", at(0.4), "N"}};
  m.outputs = {{"x_tip", at(1.0), fem::Quantity::displacement, "m"}, {"v_07", at(0.7), fem::Quantity::velocity, "m/s"}};
  return m;
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
