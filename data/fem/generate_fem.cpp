// Generates the finite-element example of data/fem/README.md into OUTDIR:
//
//   beam.json, beam.M.mtx, beam.K.mtx   the FE model (the "simulation side"): a free
//                                       aluminium bar on two isolator springs, 3 002 DOFs,
//                                       Rayleigh damping, force F at 0.3 L, velocities
//                                       at the tip and mid-span (laser vibrometer)
//                                       and a 2 g sensor bracket at the tip, modelled as
//                                       a rigid point mass
//   measured.csv (t, F, v_tip, v_mid)   the "real structure": the same bar whose bracket
//                                       is flexible — its 2 g sit on a spring (the joint
//                                       stiffness the FE model lacks) tuned to 220 Hz,
//                                       0.5 % damping — driven by a multisine, 1 % noise
//   fe_response.csv                     the FE model's own response to the same force
//                                       (8 modes, no noise): what a perfect model gives
//   truth.json                          the bracket and the mode it adds
//
//   sysid_generate_fem OUTDIR
//
// Deterministic (std::mt19937_64 with fixed seeds).
#include <sysid/core/simulate.hpp>
#include <sysid/fem/beam_model.hpp>
#include <sysid/fem/modal_model.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/fem_model_file.hpp>
#include <sysid/signal/excitation.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <random>

namespace {

constexpr double kTs = 0.5e-3;         // 2 kHz sampling
constexpr Eigen::Index kSamples = 24000;  // 12 s
constexpr int kElements = 1500;        // 3 002 DOFs
constexpr int kModes = 8;              // modes kept for the time simulation (up to ~980 Hz, below Nyquist)
constexpr double kAlpha = 10.0, kBeta = 4e-5;  // Rayleigh damping of the bar: zeta 2-4 % over 50-300 Hz
constexpr double kBracketMass = 0.002, kBracketHz = 95.0, kBracketZeta = 0.005;

/// The bar on its isolators with the sensor bracket at the tip: as the FE model has
/// it (`flexible_bracket` false: a rigid point mass) or as it is (a mass on the
/// bracket's spring, which the FE model lacks). Returns the model and (through
/// `bracket_dof`) the bracket's DOF.
sysid::fem::SecondOrderModel bar(bool flexible_bracket, Eigen::Index* bracket_dof = nullptr) {
  sysid::fem::BeamOptions o;
  o.elements = kElements;
  o.length = 1.0;
  o.flexural_rigidity = 70e9 * 0.04 * std::pow(0.01, 3) / 12.0;  // 40 x 10 mm aluminium
  o.mass_per_length = 2700.0 * 0.04 * 0.01;
  sysid::fem::StructureBuilder b(o);
  b.add_spring_to_ground(b.translation_dof(b.node_at(0.2)), 2000.0);
  b.add_spring_to_ground(b.translation_dof(b.node_at(0.8)), 2000.0);
  const Eigen::Index tip = b.translation_dof(kElements), mid = b.translation_dof(b.node_at(0.5)),
                     force = b.translation_dof(b.node_at(0.3));
  if (!flexible_bracket) {
    b.add_point_mass(tip, kBracketMass);
    if (bracket_dof != nullptr) *bracket_dof = tip;
  } else {
    const double w = 2.0 * std::numbers::pi * kBracketHz;
    const Eigen::Index r = b.add_resonator(tip, kBracketMass, kBracketMass * w * w, 2.0 * kBracketZeta * kBracketMass * w);
    if (bracket_dof != nullptr) *bracket_dof = r;
  }
  auto model = b.finish({{"F", force, "N"}}, {{"v_tip", tip, sysid::fem::Quantity::velocity, "m/s"},
                                              {"v_mid", mid, sysid::fem::Quantity::velocity, "m/s"}});
  // Rayleigh damping of the bar (for the bracket model added to its damper matrix).
  Eigen::SparseMatrix<double> rayleigh = kAlpha * model.mass + kBeta * model.stiffness;
  if (model.damping.kind == sysid::fem::DampingKind::matrix) {
    model.damping_matrix = model.damping_matrix + rayleigh;
  } else {
    model.damping.kind = sysid::fem::DampingKind::rayleigh;
    model.damping.alpha = kAlpha;
    model.damping.beta = kBeta;
  }
  return model;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: sysid_generate_fem OUTDIR\n";
    return 1;
  }
  const std::filesystem::path dir(argv[1]);
  std::filesystem::create_directories(dir);

  const auto fe_model = bar(false);
  sysid::write_fem_model((dir / "beam.json").string(), fe_model,
                              "aluminium bar 1000 x 40 x 10 mm on two isolator springs (2 kN/m at 0.2 L and 0.8 L), "
                              "Euler-Bernoulli elements; force at 0.3 L, velocities at the tip and mid-span");

  Eigen::Index bracket_dof = 0;
  const auto real_structure = bar(true, &bracket_dof);
  sysid::fem::ModalAnalysisOptions ao;
  ao.modes = kModes + 1;  // the bracket adds one mode
  sysid::fem::ModalModelOptions mo;
  mo.Ts = kTs;
  const auto truth = sysid::fem::modal_model(real_structure, ao, mo);
  // The bracket's mode: the one whose shape moves the bracket mass most (mass-normalised).
  Eigen::Index bracket_mode = 0;
  truth.modes.mode_shapes.row(bracket_dof).cwiseAbs().maxCoeff(&bracket_mode);

  sysid::MultisineOptions ms;
  ms.f_min_hz = 2.0;
  ms.f_max_hz = 400.0;
  ms.rms = 1.0;  // N
  ms.seed = 2026;
  // The structure is simulated 8 times faster than it is sampled (the multisine is
  // band-limited, so its fine-grid values are exact) and every 8th sample kept: the
  // recorded force and velocities are samples of continuous signals, as an
  // acquisition with anti-alias filters gives — not the staircase a zero-order hold
  // implies, whose half-sample delay would be a 27-degree phase error at 300 Hz.
  constexpr int kOversample = 8;
  ms.fs_hz = kOversample / kTs;
  ms.samples = kSamples * kOversample;
  const Eigen::MatrixXd u_fine = sysid::multisine(ms);
  mo.Ts = kTs / kOversample;
  const auto sampled = [&](const sysid::StateSpace& fine_model) {
    const Eigen::MatrixXd y_fine = sysid::simulate(fine_model, u_fine);
    Eigen::MatrixXd y_coarse(kSamples, y_fine.cols());
    for (Eigen::Index k = 0; k < kSamples; ++k) y_coarse.row(k) = y_fine.row(k * kOversample);
    return y_coarse;
  };
  Eigen::MatrixXd u(kSamples, 1);
  for (Eigen::Index k = 0; k < kSamples; ++k) u(k, 0) = u_fine(k * kOversample, 0);
  Eigen::MatrixXd y = sampled(sysid::fem::modal_model(real_structure, truth.modes, mo).model);
  // The FE model's own response to the same force (same modes count, no noise): the
  // reference a perfect FE model would produce.
  sysid::fem::ModalAnalysisOptions fe_modes;
  fe_modes.modes = kModes;
  const Eigen::MatrixXd y_fe = sampled(sysid::fem::modal_model(fe_model, fe_modes, mo).model);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (Eigen::Index j = 0; j < y.cols(); ++j) {
    const double rms = std::sqrt(y.col(j).squaredNorm() / static_cast<double>(kSamples));
    for (Eigen::Index k = 0; k < kSamples; ++k) y(k, j) += 0.01 * rms * noise(rng);
  }
  Eigen::MatrixXd table(kSamples, 4);
  for (Eigen::Index k = 0; k < kSamples; ++k) table(k, 0) = static_cast<double>(k) * kTs;
  table.col(1) = u.col(0);
  table.rightCols(2) = y;
  sysid::write_csv((dir / "measured.csv").string(), {"t", "F", "v_tip", "v_mid"}, table);
  table.rightCols(2) = y_fe;
  sysid::write_csv((dir / "fe_response.csv").string(), {"t", "F", "v_tip", "v_mid"}, table);
  // The same experiment with the force applied as the DAC's staircase (zero-order
  // hold at Ts): the hold a ZOH-sampled reduced model assumes, so that the model and
  // this log differ only by the bracket.
  Eigen::MatrixXd y_zoh = sysid::simulate(truth.model, u);
  for (Eigen::Index j = 0; j < y_zoh.cols(); ++j) {
    const double rms = std::sqrt(y_zoh.col(j).squaredNorm() / static_cast<double>(kSamples));
    for (Eigen::Index k = 0; k < kSamples; ++k) y_zoh(k, j) += 0.01 * rms * noise(rng);
  }
  table.rightCols(2) = y_zoh;
  sysid::write_csv((dir / "measured_zoh.csv").string(), {"t", "F", "v_tip", "v_mid"}, table);

  nlohmann::json t;
  t["missing"] = "sensor bracket at the tip: a mass on a spring the FE model lacks";
  t["bracket_mass_kg"] = kBracketMass;
  t["bracket_uncoupled_hz"] = kBracketHz;
  t["bracket_damping"] = kBracketZeta;
  t["bracket_mode_hz"] = truth.modes.natural_frequencies_hz(bracket_mode);
  t["bracket_mode_damping"] = truth.modes.damping_ratios(bracket_mode);
  // The bar's second bending mode as the bracket leaves it (the mode above the bracket's).
  t["shifted_mode_hz"] = truth.modes.natural_frequencies_hz(bracket_mode + 1);
  t["fe_dofs"] = fe_model.dofs();
  t["Ts"] = kTs;
  t["samples"] = kSamples;
  sysid::write_file_atomically((dir / "truth.json").string(), t.dump(2) + "\n");

  std::cout << "FE example in " << dir.string() << ": " << fe_model.dofs() << " DOFs; real structure's modes [Hz]:";
  for (Eigen::Index i = 0; i < truth.modes.natural_frequencies_hz.size(); ++i)
    std::cout << " " << truth.modes.natural_frequencies_hz(i) << (i == bracket_mode ? "*" : "");
  std::cout << " (* the bracket's)\n";
  return 0;
}
