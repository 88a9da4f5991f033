#pragma once
// Internal to src/pem: the prediction-error cost over scaled records and the R
// factor of [J eps], the Jacobian of the prediction errors with the errors
// appended (src/pem/pem_jacobian.cpp; method in include/sysid/pem/prediction_error.hpp).
#include <sysid/core/detail/lagged_sums.hpp>
#include <sysid/pem/polynomial_model.hpp>

#include <Eigen/Dense>

#include <optional>
#include <vector>

namespace sysid::detail::pem_impl {

/// One record in scaled units: inputs divided by their RMS, the chosen output by its.
struct ScaledRecord {
  Eigen::MatrixXd u;
  Eigen::VectorXd y;
};

/// The cost 0.5 sum eps^2 over the records; `eps`, when given, receives each record's errors.
double cost_of(const PolynomialModel& model, const std::vector<ScaledRecord>& records,
               std::vector<Eigen::VectorXd>* eps = nullptr);

/// y / C and every u_i / C of each record at one C, with the table of their
/// lagged sums: what the variable projection forms, and what the Jacobian
/// factor at the same C (after a step, the projection's model) takes instead
/// of filtering and correlating them again (a quarter of its lags on the Par2
/// ARMAX(32,32,26)).
struct FilteredByC {
  Eigen::VectorXd c;
  std::vector<std::vector<Eigen::VectorXd>> signals;  ///< per record: y / C, then u_i / C
  std::vector<detail::LaggedSumsTable> tables;        ///< per record

  /// Whether these are the signals of the model's C and the model's Jacobian
  /// starts with them in the same order (y / C, then u_i / C for every input).
  bool serves(const PolynomialModel& m) const {
    if (c.size() != m.C.size() || c != m.C || m.na() == 0 || m.nd() > 0) return false;
    for (Eigen::Index i = 0; i < m.inputs(); ++i)
      if (m.nb(i) == 0 || m.nf(i) > 0) return false;
    return true;
  }
};

/// R factor of a matrix whose columns are shifted copies of each record's
/// signals (the same columns for every record, the records stacked), from
/// their double-double Gram matrix of lagged sums summed over the records
/// (core/detail/lagged_sums.hpp, core/double_double_cholesky.hpp). `known`
/// (one per record) holds lagged sums of the records' first signals already
/// formed; `tables` receives this call's. Empty when a record is not longer
/// than the largest shift or the factorisation is refused.
std::optional<Eigen::MatrixXd> shifted_columns_factor(const std::vector<std::vector<Eigen::VectorXd>>& record_signals,
                                                      const std::vector<detail::ShiftedColumn>& columns,
                                                      const std::vector<detail::LaggedSumsTable>* known = nullptr,
                                                      std::vector<detail::LaggedSumsTable>* tables = nullptr);

/// R factor of [J eps] over all records ((p+1) x (p+1), non-negative
/// diagonal): from the Gram matrix when that is accurate, else by a streaming
/// Householder QR whose rows are made in its own buffer, chunk by chunk
/// (O(p^2) memory). `by_c`, when it serves the model, supplies y / C, u / C and
/// their lagged sums, and `eps` (one per record) the model's prediction errors.
Eigen::MatrixXd jacobian_factor(const PolynomialModel& model, const std::vector<ScaledRecord>& records, Eigen::Index p,
                                const FilteredByC* by_c = nullptr, const std::vector<Eigen::VectorXd>* eps = nullptr);

}  // namespace sysid::detail::pem_impl
