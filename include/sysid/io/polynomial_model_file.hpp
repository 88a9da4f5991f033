#pragma once
/// @file
/// Purpose: the model file (DESIGN.md "Model files") of polynomial models, one
/// per output over the same inputs: "type": "polynomial", the coefficient lists
/// and the equivalent innovation-form state space under "state_space", so any
/// reader can simulate the model.
///
/// Keys (one entry per output, in output order, so the shape does not depend
/// on the number of outputs):
///   "A": [[1, a_1, ..], ..]           "C": [[1, c_1, ..], ..]    "D": [[1, d_1, ..], ..]
///   "B": [[[b_0, ..] per input], ..]  "F": [[[1, f_1, ..] per input], ..]
///   "nk": [[delay per input], ..]     "noise_variance": [sigma^2, ..]
///   "structure": "arx" | "armax" | "oe" | "ar" | "arma" | ...
/// The polynomials are in the backward shift q^-1 (pem/polynomial_model.hpp).
/// The state space carries K (innovation form) and the noise covariance
/// diag(noise_variance).
#include <sysid/core/errors.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/config.hpp>
#include <sysid/pem/polynomial_fit.hpp>
#include <sysid/pem/polynomial_model.hpp>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace sysid {

inline ModelFile polynomial_model_file(const std::vector<PolynomialModel>& models, const std::string& structure,
                                       const std::vector<std::string>& input_names,
                                       const std::vector<std::string>& output_names) {
  const InnovationStateSpace ss = to_innovation_state_space(models);
  ModelFile file;
  file.type = "polynomial";
  file.model = ss.model;
  file.model.input_names = input_names;
  file.model.output_names = output_names;
  file.K = ss.K;
  const auto l = static_cast<Eigen::Index>(models.size());
  file.noise_covariance = Eigen::MatrixXd::Zero(l, l);
  auto list = [](const Eigen::VectorXd& v) { return nlohmann::json(std::vector<double>(v.data(), v.data() + v.size())); };
  nlohmann::json a = nlohmann::json::array(), b = nlohmann::json::array(), c = nlohmann::json::array(),
                 d = nlohmann::json::array(), f = nlohmann::json::array(), nk = nlohmann::json::array(),
                 variance = nlohmann::json::array();
  for (Eigen::Index r = 0; r < l; ++r) {
    const PolynomialModel& pm = models[static_cast<std::size_t>(r)];
    file.noise_covariance(r, r) = pm.noise_variance;
    a.push_back(list(pm.A));
    c.push_back(list(pm.C));
    d.push_back(list(pm.D));
    nlohmann::json bi = nlohmann::json::array(), fi = nlohmann::json::array();
    for (std::size_t i = 0; i < pm.B.size(); ++i) {
      bi.push_back(list(pm.B[i]));
      fi.push_back(list(pm.F[i]));
    }
    b.push_back(bi);
    f.push_back(fi);
    nk.push_back(pm.nk);
    variance.push_back(pm.noise_variance);
  }
  file.extra["structure"] = structure;
  file.extra["A"] = a;
  file.extra["B"] = b;
  file.extra["C"] = c;
  file.extra["D"] = d;
  file.extra["F"] = f;
  file.extra["nk"] = nk;
  file.extra["noise_variance"] = variance;
  return file;
}

/// The model file of a polynomial fit (pem/polynomial_fit.hpp) as every caller
/// writes it, the command line (apps/verb_polynomial.cpp) and the Python package
/// alike: polynomial_model_file, the offsets, and the provenance of the fit
/// (method, the orders the structure uses, the AR method of an AR model,
/// converged, a time series' residual_whiteness, sysid_version); the caller
/// adds what only it knows (the log's name, validation data, an order search).
inline ModelFile polynomial_fit_model_file(const PolynomialFit& fit, const PolynomialFitOptions& options,
                                           const std::vector<std::string>& input_names,
                                           const std::vector<std::string>& output_names) {
  const PolynomialStructure structure = options.structure;
  ModelFile file = polynomial_model_file(fit.models, to_string(structure), input_names, output_names);
  file.input_offset = fit.input_offset.head(fit.models.front().inputs());
  file.output_offset = fit.output_offset;
  nlohmann::json& p = file.provenance;
  p["method"] = to_string(structure);
  const PolynomialOrders& orders = options.orders;
  if (structure != PolynomialStructure::oe) p["na"] = orders.na;
  if (structure == PolynomialStructure::ar) p["ar_method"] = to_string(options.ar_method);
  if (has_inputs(structure)) {
    p["nb"] = orders.nb;
    p["nk"] = orders.nk;
  }
  if (structure == PolynomialStructure::armax || structure == PolynomialStructure::arma) p["nc"] = orders.nc;
  if (structure == PolynomialStructure::oe) p["nf"] = orders.nf;
  p["converged"] = fit.converged;
  // Per output, the Ljung-Box test of the one-step residuals on the estimation
  // data (time series only; pem/residual_whiteness.hpp): what the residual-
  // correlation warning rests on, for a reader of the file.
  if (!fit.residual_whiteness.empty()) {
    nlohmann::json tests = nlohmann::json::array();
    for (const LjungBoxTest& t : fit.residual_whiteness)
      tests.push_back({{"lags", t.lags}, {"statistic", t.statistic}, {"degrees_of_freedom", t.degrees_of_freedom},
                       {"p_value", t.p_value}});
    p["residual_whiteness"] = tests;
  }
  p["sysid_version"] = SYSID_VERSION_STRING;
  return file;
}

/// Per output, the number of estimated parameters of the noise model
/// H = C / (A D) of a polynomial model file: na + nc + nd (ARX: na; OE: 0; ARMA:
/// na + nc). They are the p of the Ljung-Box test's chi2(h - p) when the residuals
/// are the model's one-step prediction errors (Ljung & Box 1978; Box, Jenkins &
/// Reinsel, Time Series Analysis, 4th ed., sec. 8.2.2). Empty for a file that is
/// not "polynomial". Errors: sysid::DataError (naming `source_name`) when a
/// coefficient list is missing or is not a list per output.
inline std::vector<Eigen::Index> noise_model_parameter_counts(const ModelFile& file, const std::string& source_name) {
  if (file.type != "polynomial") return {};
  const Eigen::Index l = file.model.outputs();
  std::vector<Eigen::Index> counts(static_cast<std::size_t>(l), 0);
  for (const char* key : {"A", "C", "D"}) {
    const auto it = file.extra.find(key);
    if (it == file.extra.end() || !it->is_array() || it->size() != static_cast<std::size_t>(l))
      throw DataError(source_name, 0, 0,
                      std::string("polynomial model: expected \"") + key + "\" as a list of " + std::to_string(l) +
                          " coefficient lists (one per output)");
    for (std::size_t i = 0; i < counts.size(); ++i) {
      const auto& poly = (*it)[i];
      if (!poly.is_array() || poly.empty())
        throw DataError(source_name, 0, 0, std::string("polynomial model: \"") + key + "\"[" + std::to_string(i) +
                                               "] must be a non-empty list of coefficients [1, ...]");
      counts[i] += static_cast<Eigen::Index>(poly.size()) - 1;  // the leading 1 is not estimated
    }
  }
  return counts;
}

}  // namespace sysid
