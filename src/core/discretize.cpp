// Implementation of core/discretize.hpp (method and references in the header).
// Compiled once into libsysid: Eigen's matrix exponential and logarithm
// (MatrixFunctions, Schur-Parlett) are heavy to instantiate.
#include <sysid/core/discretize.hpp>
#include <sysid/core/format_number.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>

namespace sysid {

namespace {

/// The preconditions shared by the c2d conversions.
void check_sampling(const StateSpace& continuous, double Ts, const std::string& who) {
  continuous.validate();
  if (continuous.Ts != 0.0) throw std::invalid_argument(who + ": need a continuous model (Ts == 0)");
  if (!(Ts > 0.0) || !std::isfinite(Ts)) throw std::invalid_argument(who + ": need sample time Ts > 0");
}

}  // namespace

StateSpace c2d_zoh(const StateSpace& continuous, double Ts) {
  check_sampling(continuous, Ts, "c2d_zoh");
  const Eigen::Index n = continuous.order(), m = continuous.inputs();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + m, n + m);
  M.topLeftCorner(n, n) = continuous.A * Ts;
  M.topRightCorner(n, m) = continuous.B * Ts;
  const Eigen::MatrixXd E = M.exp();
  if (!E.allFinite()) throw NumericalError("c2d_zoh: matrix exponential overflowed (A Ts too large)");
  StateSpace d(E.topLeftCorner(n, n), E.topRightCorner(n, m), continuous.C, continuous.D, Ts);
  d.input_names = continuous.input_names;
  d.output_names = continuous.output_names;
  return d;
}

StateSpace c2d_foh(const StateSpace& continuous, double Ts) {
  check_sampling(continuous, Ts, "c2d_foh");
  const Eigen::Index n = continuous.order(), m = continuous.inputs();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + 2 * m, n + 2 * m);
  M.topLeftCorner(n, n) = continuous.A * Ts;
  M.block(0, n, n, m) = continuous.B * Ts;
  M.block(n, n + m, m, m) = Eigen::MatrixXd::Identity(m, m);
  const Eigen::MatrixXd E = M.exp();
  if (!E.allFinite()) throw NumericalError("c2d_foh: matrix exponential overflowed (A Ts too large)");
  const Eigen::MatrixXd Phi = E.topLeftCorner(n, n), G1 = E.block(0, n, n, m), G2 = E.block(0, n + m, n, m);
  const Eigen::MatrixXd Bd = G1 + Phi * G2 - G2;
  StateSpace d(Phi, Bd, continuous.C, continuous.D + continuous.C * G2, Ts);
  d.input_names = continuous.input_names;
  d.output_names = continuous.output_names;
  return d;
}

StateSpace c2d(const StateSpace& continuous, double Ts, Hold hold) {
  return hold == Hold::foh ? c2d_foh(continuous, Ts) : c2d_zoh(continuous, Ts);
}

StateSpace model_at_sample_time(const StateSpace& model, double Ts, Hold hold, const std::string& source) {
  if (!model.is_discrete()) return c2d(model, Ts, hold);
  if (std::abs(model.Ts - Ts) > 1e-6 * model.Ts)
    throw DataError(source, 0, 0,
                    "the model's sample time " + format_number(model.Ts, 9) + " s differs from the log's " +
                        format_number(Ts, 9) + " s; a discrete-time model runs only at its own rate");
  return model;
}

StateSpace d2c_zoh(const StateSpace& discrete) {
  discrete.validate();
  if (!discrete.is_discrete()) throw std::invalid_argument("d2c_zoh: need a discrete model (Ts > 0)");
  const Eigen::Index n = discrete.order(), m = discrete.inputs();
  const double Ts = discrete.Ts;
  const Eigen::VectorXcd p = poles(discrete);
  const double eps = std::numeric_limits<double>::epsilon();
  const double scale = n > 0 ? discrete.A.cwiseAbs().maxCoeff() : 0.0;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    const bool at_zero = std::abs(p[i]) <= static_cast<double>(n) * eps * scale;
    const bool negative_real = p[i].real() < 0.0 && std::abs(p[i].imag()) <= std::sqrt(eps) * std::abs(p[i]);
    if (at_zero || negative_real)
      throw NumericalError("d2c_zoh: discrete pole " + format_number(p[i].real()) + (p[i].imag() >= 0 ? "+" : "") +
                           format_number(p[i].imag()) +
                           "j is on the negative real axis or at 0: no continuous-time ZOH equivalent");
  }
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(n + m, n + m);
  M.topLeftCorner(n, n) = discrete.A;
  M.topRightCorner(n, m) = discrete.B;
  const Eigen::MatrixXd L = M.log();
  if (!L.allFinite()) throw NumericalError("d2c_zoh: matrix logarithm failed");
  // A tiny Ts (a file may say 5e-324) overflows log(Phi) / Ts: a numerical limit of
  // the conversion, not a malformed model.
  const Eigen::MatrixXd Ac = L.topLeftCorner(n, n) / Ts, Bc = L.topRightCorner(n, m) / Ts;
  if (!Ac.allFinite() || !Bc.allFinite())
    throw NumericalError("d2c_zoh: log(Phi) / Ts overflows at Ts = " + std::to_string(Ts) + " s");
  StateSpace c(Ac, Bc, discrete.C, discrete.D, 0.0);
  c.input_names = discrete.input_names;
  c.output_names = discrete.output_names;
  return c;
}

}  // namespace sysid
