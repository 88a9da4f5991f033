#include "sysid/fem/beam_model.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace sysid::fem {

StructureBuilder::StructureBuilder(const BeamOptions& options) : m_options(options) {
  if (options.elements < 1) throw std::invalid_argument("beam: need elements >= 1");
  if (!(options.length > 0.0) || !(options.flexural_rigidity > 0.0) || !(options.mass_per_length > 0.0))
    throw std::invalid_argument("beam: need length, flexural_rigidity and mass_per_length > 0");
  const int nodes = options.elements + 1;
  m_dofs = 2 * nodes - (options.clamped_left ? 2 : 0);
  const double h = options.length / options.elements;
  const double k0 = options.flexural_rigidity / (h * h * h), m0 = options.mass_per_length * h / 420.0;
  // Element matrices in the local order (w1, theta1, w2, theta2); see the header.
  const double ke[4][4] = {{12, 6 * h, -12, 6 * h},
                           {6 * h, 4 * h * h, -6 * h, 2 * h * h},
                           {-12, -6 * h, 12, -6 * h},
                           {6 * h, 2 * h * h, -6 * h, 4 * h * h}};
  const double me[4][4] = {{156, 22 * h, 54, -13 * h},
                           {22 * h, 4 * h * h, 13 * h, -3 * h * h},
                           {54, 13 * h, 156, -22 * h},
                           {-13 * h, -3 * h * h, -22 * h, 4 * h * h}};
  const Eigen::Index shift = options.clamped_left ? 2 : 0;
  m_mass.reserve(static_cast<std::size_t>(16 * options.elements));
  m_stiffness.reserve(static_cast<std::size_t>(16 * options.elements));
  for (int e = 0; e < options.elements; ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        // Global DOF before removing the clamped ones; clamped DOFs simply drop out.
        const Eigen::Index i = 2 * e + a - shift, j = 2 * e + b - shift;
        if (i < 0 || j < 0) continue;
        add(m_stiffness, i, j, k0 * ke[a][b]);
        add(m_mass, i, j, m0 * me[a][b]);
      }
}

void StructureBuilder::add(std::vector<Eigen::Triplet<double>>& target, Eigen::Index i, Eigen::Index j, double value) {
  target.emplace_back(i, j, value);
}

Eigen::Index StructureBuilder::translation_dof(int node) const {
  if (node < 0 || node > m_options.elements)
    throw std::invalid_argument("beam: node " + std::to_string(node) + " outside 0.." + std::to_string(m_options.elements));
  if (node == 0 && m_options.clamped_left) throw std::invalid_argument("beam: node 0 is clamped and has no DOF");
  return 2 * static_cast<Eigen::Index>(node) - (m_options.clamped_left ? 2 : 0);
}

int StructureBuilder::node_at(double x) const {
  if (!(x >= 0.0 && x <= m_options.length)) throw std::invalid_argument("beam: position outside 0..length");
  return static_cast<int>(std::lround(x / m_options.length * m_options.elements));
}

void StructureBuilder::add_point_mass(Eigen::Index dof, double mass) {
  if (dof < 0 || dof >= m_dofs || !(mass >= 0.0)) throw std::invalid_argument("beam: bad point mass");
  add(m_mass, dof, dof, mass);
}

void StructureBuilder::add_spring_to_ground(Eigen::Index dof, double stiffness, double damping) {
  if (dof < 0 || dof >= m_dofs || !(stiffness >= 0.0) || !(damping >= 0.0))
    throw std::invalid_argument("beam: bad spring to ground");
  add(m_stiffness, dof, dof, stiffness);
  if (damping > 0.0) add(m_damping, dof, dof, damping);
}

Eigen::Index StructureBuilder::add_resonator(Eigen::Index dof, double mass, double stiffness, double damping) {
  if (dof < 0 || dof >= m_dofs || !(mass > 0.0) || !(stiffness > 0.0) || !(damping >= 0.0))
    throw std::invalid_argument("beam: bad resonator");
  const Eigen::Index r = m_dofs++;
  add(m_mass, r, r, mass);
  // The spring (and damper) between dof and r: [k -k; -k k].
  for (auto* target : {&m_stiffness, &m_damping}) {
    const double v = target == &m_stiffness ? stiffness : damping;
    if (v == 0.0) continue;
    add(*target, dof, dof, v);
    add(*target, r, r, v);
    add(*target, dof, r, -v);
    add(*target, r, dof, -v);
  }
  return r;
}

SecondOrderModel StructureBuilder::finish(std::vector<ForceInput> inputs, std::vector<DofOutput> outputs) const {
  SecondOrderModel model;
  model.mass.resize(m_dofs, m_dofs);
  model.stiffness.resize(m_dofs, m_dofs);
  model.mass.setFromTriplets(m_mass.begin(), m_mass.end());  // duplicates are summed: assembly
  model.stiffness.setFromTriplets(m_stiffness.begin(), m_stiffness.end());
  if (!m_damping.empty()) {
    model.damping_matrix.resize(m_dofs, m_dofs);
    model.damping_matrix.setFromTriplets(m_damping.begin(), m_damping.end());
    model.damping.kind = DampingKind::matrix;
  }
  model.inputs = std::move(inputs);
  model.outputs = std::move(outputs);
  return model;
}

Eigen::VectorXd cantilever_frequencies_hz(const BeamOptions& options, int count) {
  if (count < 1) throw std::invalid_argument("cantilever_frequencies_hz: need count >= 1");
  Eigen::VectorXd f(count);
  for (int i = 1; i <= count; ++i) {
    // Root of g(b) = cos b cosh b + 1 near (2i - 1) pi / 2; Newton converges in a few
    // steps (for large i the asymptote is already exact to double precision).
    double b = (2.0 * i - 1.0) * std::numbers::pi / 2.0;
    for (int it = 0; it < 50; ++it) {
      const double g = std::cos(b) * std::cosh(b) + 1.0;
      const double dg = -std::sin(b) * std::cosh(b) + std::cos(b) * std::sinh(b);
      const double step = g / dg;
      b -= step;
      if (std::abs(step) < 1e-15 * b) break;
    }
    f(i - 1) = b * b / (2.0 * std::numbers::pi * options.length * options.length) *
               std::sqrt(options.flexural_rigidity / options.mass_per_length);
  }
  return f;
}

}  // namespace sysid::fem
