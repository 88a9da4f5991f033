// The detectors' shared view of the residual; see detection_context.hpp.
#include "diagnose/detail/detection_context.hpp"

#include "sysid/core/format_number.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sysid {

namespace {

ModalBasis modal_basis(const AugmentedSimulator& simulator) {
  ModalBasis basis;
  const auto& continuous = simulator.continuous_equivalent();
  if (!continuous) return basis;
  Eigen::EigenSolver<Eigen::MatrixXd> eig(continuous->A);
  if (eig.info() != Eigen::Success) return basis;
  const Eigen::MatrixXcd V = eig.eigenvectors();
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXcd>(V).singularValues();
  if (!(sv(sv.size() - 1) > 1e-10 * sv(0))) return basis;
  basis.poles = eig.eigenvalues();
  basis.output_shapes = continuous->C.cast<std::complex<double>>() * V;
  basis.input_shapes = V.partialPivLu().solve(continuous->B.cast<std::complex<double>>());
  return basis;
}

/// The running integral of x (rectangle rule, step Ts) with its mean removed.
Eigen::VectorXd integral(const Eigen::VectorXd& x, double Ts) {
  Eigen::VectorXd s(x.size());
  double sum = 0.0;
  for (Eigen::Index k = 0; k < x.size(); ++k) s[k] = (sum += x[k] * Ts);
  s.array() -= s.mean();
  return s;
}

/// The backward difference of x over Ts (the first sample's is 0).
Eigen::VectorXd difference(const Eigen::VectorXd& x, double Ts) {
  Eigen::VectorXd d = Eigen::VectorXd::Zero(x.size());
  if (x.size() > 1) d.tail(x.size() - 1) = (x.tail(x.size() - 1) - x.head(x.size() - 1)) / Ts;
  return d;
}

}  // namespace

DetectionContext::DetectionContext(const DetectionData& data, const DetectionOptions& options,
                                   const AugmentedSimulator* reading)
    : m_data(data), m_options(options), m_simulator(reading ? reading : data.simulator), m_basis(modal_basis(*data.simulator)) {
  m_rows = data.y.rows();
  const Eigen::Index l = data.y.cols();
  m_output_weight.resize(l);
  for (Eigen::Index i = 0; i < l; ++i) {
    const double sd = std::sqrt((data.y.col(i).array() - data.y.col(i).mean()).square().mean());
    m_output_weight[i] = 1.0 / std::max(sd, kTinyScale);
  }
  m_residual = data.y - data.current;
  m_residual_energy = weighted(m_residual).squaredNorm();
}

OutputQuantity DetectionContext::quantity(long output) const { return m_simulator->output_quantity(output); }

Eigen::VectorXd DetectionContext::weighted(const Eigen::MatrixXd& signal) const {
  Eigen::MatrixXd w = signal * m_output_weight.asDiagonal();
  return Eigen::Map<const Eigen::VectorXd>(w.data(), w.size());
}

Eigen::VectorXd DetectionContext::effect(const PhysicsBlock& block) const {
  std::vector<PhysicsBlock> blocks = m_data.accepted;
  blocks.push_back(block);
  return weighted(m_simulator->simulate(blocks, m_data.u, m_rows) - m_data.current);
}

double DetectionContext::explained_as_is(const Eigen::VectorXd& change) const {
  const Eigen::VectorXd r = weighted(m_residual);
  return m_residual_energy > 0 ? 1.0 - (r - change).squaredNorm() / m_residual_energy : 0.0;
}

std::pair<Eigen::VectorXd, double> DetectionContext::regress(const Eigen::MatrixXd& G) const {
  const Eigen::VectorXd r = weighted(m_residual);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(G);
  if (qr.rank() < G.cols() || m_residual_energy <= 0) return {Eigen::VectorXd::Zero(G.cols()), 0.0};
  const Eigen::VectorXd c = qr.solve(r);
  return {c, 1.0 - (r - G * c).squaredNorm() / m_residual_energy};
}

Eigen::MatrixXd DetectionContext::sensitivities(const PhysicsBlock& block,
                                                const std::vector<std::pair<std::string, double>>& probes) const {
  Eigen::MatrixXd G(m_rows * outputs(), static_cast<Eigen::Index>(probes.size()));
  for (std::size_t k = 0; k < probes.size(); ++k) {
    PhysicsBlock probed = block;
    probed.params[probes[k].first] += probes[k].second;
    G.col(static_cast<Eigen::Index>(k)) = effect(probed) / probes[k].second;
  }
  return G;
}

Eigen::VectorXd reading_position(const Eigen::VectorXd& y, OutputQuantity q, double Ts) {
  switch (q) {
    case OutputQuantity::velocity: return integral(y, Ts);
    case OutputQuantity::acceleration: return integral(integral(y, Ts), Ts);
    default: return y;
  }
}

Eigen::VectorXd reading_velocity(const Eigen::VectorXd& y, OutputQuantity q, double Ts) {
  switch (q) {
    case OutputQuantity::velocity: return y;
    case OutputQuantity::acceleration: return integral(y, Ts);
    default: return difference(y, Ts);
  }
}

Eigen::VectorXd DetectionContext::position(long output) const {
  return reading_position(m_data.current.col(output), quantity(output), Ts());
}

Eigen::VectorXd DetectionContext::velocity(long output) const {
  return reading_velocity(m_data.current.col(output), quantity(output), Ts());
}

Candidate DetectionContext::linearised(PhysicsBlock block, const std::string& name, double p0, double delta,
                                       FreeParameter bound, int substeps, const std::string& what) const {
  block.params[name] = p0;
  const auto [coefficient, explained] = regress(sensitivities(block, {{name, delta}}));
  Candidate cand;
  const double start = std::clamp(p0 + coefficient[0], bound.lower, bound.upper);
  block.params[name] = bound.log_scale ? std::max(start, bound.lower) : start;
  cand.block = block;
  cand.free = {bound};
  cand.substeps = substeps;
  cand.detector_score = std::max(0.0, explained);
  cand.evidence = what + " explains " + percent(cand.detector_score) + " of the residual energy (linearised)";
  return cand;
}

Candidate DetectionContext::best_as_is(const std::vector<PhysicsBlock>& grid) const {
  Candidate best;
  best.block = grid.front();
  best.detector_score = -std::numeric_limits<double>::infinity();
  for (const auto& b : grid) {
    const double explained = explained_as_is(effect(b));
    if (explained > best.detector_score) best.block = b, best.detector_score = explained;
  }
  return best;
}

PhysicsBlock make_block(const std::string& kind, long input, long output) {
  PhysicsBlock b;
  b.kind = kind;
  b.input = input;
  b.output = output;
  for (const char* name : b.info().parameters) b.params[name] = 0.0;
  return b;
}

double rms(const Eigen::VectorXd& x) { return std::sqrt(x.squaredNorm() / std::max<double>(1, static_cast<double>(x.size()))); }

bool varies(const DetectionContext& c, long input) {
  const auto u = c.data().u.col(input);
  return rms(u) > 0 && u.maxCoeff() > u.minCoeff();
}

std::string percent(double fraction) { return format_number(100.0 * fraction, 3) + " %"; }

}  // namespace sysid
