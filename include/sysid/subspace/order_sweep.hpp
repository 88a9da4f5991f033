#pragma once
/// @file
/// Purpose: choose the model order by validation: identify one model per order
/// lo..hi with the same subspace settings and report the simulation fit of each
/// on estimation and on validation data (the "fit versus order" table of Fig. 16
/// of the Par2 paper). Unlike the singular-value rules of order_selection.hpp it
/// measures what the user cares about, the fit on data the model never saw.
///
/// Method: one n4sid() per order with the SAME horizon for all orders, chosen for
/// the largest order `hi` (so the orders differ only in the truncation of the same
/// SVD, and a difference in fit is due to the order alone): order hi is identified
/// first with base.horizon (0 = n4sid's automatic choice for order hi), and the
/// horizon it used is then imposed on every other order. Validation is by
/// simulation from an x0 estimated on the validation data (validate/compare.hpp),
/// with the offsets of each identified model removed.
///
/// Preconditions: 1 <= lo <= hi; estimation and validation have the same channels
/// and sample time; base.order is ignored. Violations throw std::invalid_argument.
/// Numerical aspects: (hi - lo + 1) identifications; each recompresses the Hankel
/// matrix, so the cost is (hi - lo + 1) times one n4sid() at horizon(hi).
#include <sysid/core/errors.hpp>
#include <sysid/core/io_data.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/subspace/n4sid.hpp>
#include <sysid/validate/compare.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

struct OrderSweepEntry {
  int order = 0;
  Eigen::VectorXd estimation_fit;  ///< per output, simulation fit on the estimation data (n4sid's own)
  Eigen::VectorXd validation_fit;  ///< per output, simulation fit on the validation data, x0 estimated
  std::vector<std::string> warnings;  ///< n4sid's warnings, or why this order failed (then the fits are NaN)
  bool ok = false;                    ///< false when the identification failed (NumericalError) at this order
  /// Largest |pole| of the model (when ok): >= 1 is an unstable model, whose
  /// simulation fit says little (an order too high for a stable plant often is).
  double spectral_radius = std::numeric_limits<double>::quiet_NaN();
  N4sidResult result;                 ///< the identified model and diagnostics (when ok)

  /// Mean validation fit over the outputs (NaN when the order failed).
  double mean_validation_fit() const {
    return ok && validation_fit.size() > 0 ? validation_fit.mean() : std::numeric_limits<double>::quiet_NaN();
  }
};

/// Horizon for the sweep when n4sid() fails at order `hi` (so its choice is not
/// known): n4sid's automatic horizon for a given order (detail::automatic_horizon),
/// shortened for short data by the same rule as n4sid.
inline int order_sweep_horizon(const IoData& data, int hi, int max_order) {
  return detail::record_limited_horizon(detail::automatic_horizon(hi, max_order, data.outputs()), data);
}

/// Purpose: the order sweep described in the file comment.
/// Returns one entry per order lo..hi, in increasing order. An order at which the
/// identification fails numerically (NumericalError, e.g. the order exceeds the
/// rank the data support) is kept with ok = false, NaN fits and the reason in its
/// warnings; every other exception propagates (bad data, bad options).
/// Example: `auto table = n4sid_order_sweep(est, val, {}, 1, 12);`
inline std::vector<OrderSweepEntry> n4sid_order_sweep(const IoData& estimation, const IoData& validation, N4sidOptions base,
                                                      int lo, int hi) {
  if (lo < 1) throw std::invalid_argument("order sweep: need lo >= 1");
  if (hi < lo) throw std::invalid_argument("order sweep: need lo <= hi (" + std::to_string(lo) + " > " + std::to_string(hi) + ")");
  estimation.validate();
  validation.validate();
  if (validation.inputs() != estimation.inputs() || validation.outputs() != estimation.outputs())
    throw std::invalid_argument("order sweep: estimation and validation data have different channels");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto identify = [&](int order, const N4sidOptions& options_for_order) {
    OrderSweepEntry entry;
    entry.order = order;
    N4sidOptions options = options_for_order;
    options.order = order;
    try {
      entry.result = n4sid(estimation, options);
    } catch (const NumericalError& e) {
      entry.warnings.push_back(std::string("order ") + std::to_string(order) + " failed: " + e.what());
      entry.estimation_fit = Eigen::VectorXd::Constant(estimation.outputs(), nan);
      entry.validation_fit = Eigen::VectorXd::Constant(estimation.outputs(), nan);
      return entry;
    }
    entry.ok = true;
    entry.spectral_radius = entry.result.model.A.size() > 0 ? poles(entry.result.model).cwiseAbs().maxCoeff() : 0.0;
    entry.warnings = entry.result.warnings;
    entry.estimation_fit = entry.result.fit_percent;
    CompareOptions co;
    co.input_offset = entry.result.input_offset;
    co.output_offset = entry.result.output_offset;
    entry.validation_fit = compare_fit(entry.result.model, entry.result.K, validation, co);
    return entry;
  };
  // Order hi first: the horizon n4sid picks for it is the one for all.
  OrderSweepEntry top = identify(hi, base);
  if (base.horizon == 0) base.horizon = top.ok ? top.result.horizon : order_sweep_horizon(estimation, hi, base.max_order);
  std::vector<OrderSweepEntry> table;
  for (int order = lo; order < hi; ++order) table.push_back(identify(order, base));
  table.push_back(std::move(top));
  return table;
}

}  // namespace sysid
