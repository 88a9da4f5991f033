#pragma once
/// @file
/// Purpose: one entry point for every polynomial structure (ARX, AR, ARMAX,
/// ARMA, OE) on all outputs of a log ("stacked MISO": one model per output over
/// all inputs), so the CLI verbs and the order search fit models the same way.
///
/// Method: ARX and AR by pem/arx.hpp (linear least squares, Burg, Yule-Walker);
/// ARMAX, ARMA and OE by pem/prediction_error.hpp, one minimisation per output.
/// The loss reported for the information criteria is the mean squared one-step
/// prediction error of each output's model on the estimation data (the maximum
/// likelihood noise variance, Ljung 1999, eq. 7.64): each method's residual
/// variance times (N - p) / N.
#include <sysid/core/io_data.hpp>
#include <sysid/pem/arx.hpp>
#include <sysid/pem/polynomial_model.hpp>
#include <sysid/pem/prediction_error.hpp>
#include <sysid/core/ljung_box.hpp>

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

enum class PolynomialStructure { arx, ar, armax, arma, oe };

/// "arx", "ar", "armax", "arma", "oe".
const char* to_string(PolynomialStructure s);
/// True for the structures with inputs (ARX, ARMAX, OE).
bool has_inputs(PolynomialStructure s);

struct PolynomialOrders {
  int na = 0;           ///< A (ARX, AR, ARMAX, ARMA); ignored by OE
  int nc = 0;           ///< C (ARMAX, ARMA)
  std::vector<int> nb;  ///< per input (ARX, ARMAX, OE)
  std::vector<int> nf;  ///< per input (OE)
  std::vector<int> nk;  ///< per input delays; empty = 1 for every input
};

struct PolynomialFitOptions {
  PolynomialStructure structure = PolynomialStructure::arx;
  PolynomialOrders orders;
  ArMethod ar_method = ArMethod::least_squares;  ///< AR only
  int max_iterations = PemOptions{}.max_iterations;  ///< ARMAX, ARMA, OE
};

struct PolynomialFit {
  std::vector<PolynomialModel> models;  ///< one per output, original units
  Eigen::VectorXd input_offset, output_offset;
  bool converged = true;  ///< every output's minimisation converged (always true for ARX/AR)
  /// Per output, in words: "linear least squares" or iterations, status and termination.
  std::vector<std::string> method_notes;
  std::vector<double> loss;  ///< per output: mean squared one-step prediction error on the estimation data
  Eigen::Index parameters = 0;  ///< estimated coefficients of all outputs' models
  Eigen::Index samples = 0;     ///< estimation samples (all experiments)
  /// Time series (AR, ARMA) only, per output: the Ljung-Box test of the one-step
  /// residuals on the estimation data (pem/residual_whiteness.hpp). A residual
  /// that is not white at level 0.1 % (over the outputs, Bonferroni) warns: the
  /// model leaves correlation in the record, and least squares, Yule-Walker and
  /// Burg then bias the poles when the cause is measurement noise (modified
  /// Yule-Walker estimates are tested but not warned of: their residual A(q) y
  /// is coloured by that noise by design). A record too short to test gives
  /// lags = 0, p = 1.
  std::vector<LjungBoxTest> residual_whiteness;
  std::vector<std::string> warnings;
};

/// Fits the structure on every output of `data` (mean-removed; offsets in the result).
/// Throws std::invalid_argument for bad orders, as the fitting functions do.
PolynomialFit fit_polynomial(const IoData& data, const PolynomialFitOptions& options);

}  // namespace sysid
