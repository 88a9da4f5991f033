#pragma once
/// @file
/// Purpose: the linear state-space model every sysid algorithm returns and consumes.
///
///   discrete (Ts > 0):   x[k+1] = A x[k] + B u[k],   y[k] = C x[k] + D u[k]
///   continuous (Ts = 0): dx/dt  = A x + B u,          y    = C x + D u
///
/// Signals are stored with samples in rows (N x channels), the same layout as the
/// columns of a CSV log, so a log column maps to a matrix column without copies.
#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

struct StateSpace {
  Eigen::MatrixXd A;  ///< n x n
  Eigen::MatrixXd B;  ///< n x m
  Eigen::MatrixXd C;  ///< l x n
  Eigen::MatrixXd D;  ///< l x m
  double Ts = 0.0;    ///< sample time in seconds; 0 means continuous time
  std::vector<std::string> input_names;   ///< m names (may be empty: then u1..um)
  std::vector<std::string> output_names;  ///< l names (may be empty: then y1..yl)

  StateSpace() = default;
  StateSpace(Eigen::MatrixXd a, Eigen::MatrixXd b, Eigen::MatrixXd c, Eigen::MatrixXd d, double ts)
      : A(std::move(a)), B(std::move(b)), C(std::move(c)), D(std::move(d)), Ts(ts) {
    validate();
  }

  Eigen::Index order() const { return A.rows(); }
  Eigen::Index inputs() const { return B.cols(); }
  Eigen::Index outputs() const { return C.rows(); }
  bool is_discrete() const { return Ts > 0.0; }

  /// Name of input j / output i, falling back to u1.. / y1.. when names are absent.
  std::string input_name(Eigen::Index j) const {
    return j < static_cast<Eigen::Index>(input_names.size()) ? input_names[j] : "u" + std::to_string(j + 1);
  }
  std::string output_name(Eigen::Index i) const {
    return i < static_cast<Eigen::Index>(output_names.size()) ? output_names[i] : "y" + std::to_string(i + 1);
  }
  /// Every input's / output's name, u1.. / y1.. where absent.
  std::vector<std::string> input_names_or_defaults() const {
    std::vector<std::string> names;
    for (Eigen::Index j = 0; j < inputs(); ++j) names.push_back(input_name(j));
    return names;
  }
  std::vector<std::string> output_names_or_defaults() const {
    std::vector<std::string> names;
    for (Eigen::Index i = 0; i < outputs(); ++i) names.push_back(output_name(i));
    return names;
  }

  /// Throws std::invalid_argument naming the first inconsistent dimension or a
  /// non-finite entry, so a bad model never reaches an algorithm.
  void validate() const {
    const auto n = A.rows();
    if (A.cols() != n) throw std::invalid_argument("state-space: A must be square, is " + dims(A));
    if (B.rows() != n) throw std::invalid_argument("state-space: B must have " + std::to_string(n) + " rows, is " + dims(B));
    if (C.cols() != n) throw std::invalid_argument("state-space: C must have " + std::to_string(n) + " columns, is " + dims(C));
    if (D.rows() != C.rows() || D.cols() != B.cols())
      throw std::invalid_argument("state-space: D must be " + std::to_string(C.rows()) + "x" + std::to_string(B.cols()) + ", is " + dims(D));
    // No inputs is allowed: a time-series (AR/ARMA) model is all noise model.
    if (C.rows() == 0) throw std::invalid_argument("state-space: need at least one output");
    if (!(Ts >= 0.0) || !std::isfinite(Ts)) throw std::invalid_argument("state-space: Ts must be >= 0 and finite");
    if (!A.allFinite() || !B.allFinite() || !C.allFinite() || !D.allFinite())
      throw std::invalid_argument("state-space: matrices contain NaN or Inf");
    if (!input_names.empty() && static_cast<Eigen::Index>(input_names.size()) != B.cols())
      throw std::invalid_argument("state-space: " + std::to_string(input_names.size()) + " input names for " + std::to_string(B.cols()) + " inputs");
    if (!output_names.empty() && static_cast<Eigen::Index>(output_names.size()) != C.rows())
      throw std::invalid_argument("state-space: " + std::to_string(output_names.size()) + " output names for " + std::to_string(C.rows()) + " outputs");
  }

 private:
  static std::string dims(const Eigen::MatrixXd& m) { return std::to_string(m.rows()) + "x" + std::to_string(m.cols()); }
};

}  // namespace sysid
