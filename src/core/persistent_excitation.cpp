// Order of persistent excitation (see include/sysid/core/persistent_excitation.hpp).
#include "sysid/core/persistent_excitation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "sysid/core/detail/lagged_sums.hpp"
#include "sysid/core/errors.hpp"

namespace sysid {

ExcitationOrder excitation_order(const IoData& data, Eigen::Index input, const ExcitationOrderOptions& o) {
  if (input < 0 || input >= data.inputs()) throw std::invalid_argument("excitation_order: no such input");
  if (o.max_order < 1) throw std::invalid_argument("excitation_order: need max_order >= 1");
  const Eigen::Index n = o.max_order;

  // Mean over everything used, then the Hankel rows of each long-enough experiment.
  double sum = 0.0, count = 0.0;
  Eigen::Index rows = 0;
  for (const auto& e : data.experiments) {
    if (e.samples() < n) continue;
    const Eigen::Index r = std::min(e.samples() - n + 1, std::max<Eigen::Index>(o.max_samples - rows, 0));
    if (r == 0) break;
    sum += e.u.col(input).head(r + n - 1).sum();
    count += static_cast<double>(r + n - 1);
    rows += r;
  }
  if (rows == 0) throw std::invalid_argument("excitation_order: every experiment is shorter than max_order");
  const double mean = sum / count;

  // Gram matrix of the Hankel matrix (columns u(t), .., u(t + n - 1), rows t of
  // every experiment) from correlation sums, O(rows n) instead of the O(rows n^2)
  // of a QR. Its eigenvalues are the squared singular values; rounding puts a
  // floor of about sqrt(n eps) ~ 1e-7 (n <= 256) under the relative singular
  // values, far below the decision threshold `tolerance` (1e-3) (see below).
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n, n);
  Eigen::Index at = 0;
  for (const auto& e : data.experiments) {
    if (e.samples() < n || at == rows) continue;
    const Eigen::Index r = std::min(e.samples() - n + 1, rows - at);
    const Eigen::VectorXd centred = e.u.col(input).head(r + n - 1).array() - mean;
    gram += detail::lagged_sums(centred, centred, n, r, true);
    at += r;
  }

  ExcitationOrder result;
  if (gram.diagonal().maxCoeff() == 0.0) return result;  // constant
  const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(gram, Eigen::EigenvaluesOnly).eigenvalues();
  // Descending; a Hankel matrix of fewer rows than columns has only `rows` of them.
  result.singular_values = eigenvalues.reverse().head(std::min(rows, n)).cwiseMax(0.0).cwiseSqrt();
  result.singular_values /= result.singular_values(0);
  // k sinusoids give an exact rank 2k plus noise: the order ends at a drop of 40 dB
  // or more to below the tolerance. A smooth decay (continuous spectrum) is exciting.
  // Below the rounding floor of the Gram route (about 3 sqrt(n eps) relative)
  // the values are noise, and clamped negative eigenvalues would fake a cliff:
  // a 100x drop is resolved only from a value 100 times above that floor.
  const Eigen::VectorXd& sv = result.singular_values;
  const double resolved = 100.0 * 3.0 * std::sqrt(static_cast<double>(n) * std::numeric_limits<double>::epsilon());
  result.order = n;
  for (Eigen::Index k = 0; k + 1 < sv.size() && sv(k) >= resolved; ++k)
    if (sv(k + 1) < o.tolerance && sv(k + 1) < 1e-2 * sv(k)) {
      result.order = k + 1;
      break;
    }
  if (sv.size() < n) result.order = std::min(result.order, sv.size());
  return result;
}

std::vector<std::string> insufficient_excitation_warnings(const IoData& data, Eigen::Index required_order,
                                                          const std::string& model, const std::string& who) {
  std::vector<std::string> out;
  if (required_order < 1) return out;
  Eigen::Index longest = 0;
  for (const auto& e : data.experiments) longest = std::max(longest, e.samples());
  if (longest < required_order) return out;
  // The test costs O(rows n^2) for n Hankel columns: it looks up to
  // kLargestCheckedOrder only (a long FIR, e.g. 2048 LMS taps, would take minutes).
  // An input exciting that many orders is almost always broadband; a multisine of
  // more lines than that but fewer than required_order / 2 goes unflagged.
  constexpr Eigen::Index kLargestCheckedOrder = 256;
  ExcitationOrderOptions o;
  o.max_order = std::min(required_order, kLargestCheckedOrder);
  for (Eigen::Index j = 0; j < data.inputs(); ++j) {
    const ExcitationOrder pe = excitation_order(data, j, o);
    if (pe.order == 0 || pe.order >= o.max_order) continue;
    out.push_back((who.empty() ? std::string() : who + ": ") + "input " + data.input_name(j) +
                  " is persistently exciting of order " + std::to_string(pe.order) + " only (" +
                  (pe.order <= 2 ? "a single sine" : "about " + std::to_string(pe.order / 2) + " sines") + "), but " +
                  model + " needs order " + std::to_string(required_order) +
                  ": the data determine the model only at the excited frequencies and the rest is noise; add "
                  "frequencies to the excitation or lower the order");
  }
  return out;
}

void require_varying_inputs(const IoData& data, const std::string& who) {
  for (Eigen::Index j = 0; j < data.inputs(); ++j) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& e : data.experiments) {
      if (e.samples() == 0) continue;
      lo = std::min(lo, e.u.col(j).minCoeff());
      hi = std::max(hi, e.u.col(j).maxCoeff());
    }
    if (hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi)))
      throw DataError((who.empty() ? std::string() : who + ": ") + "input '" + data.input_name(j) +
                      "' is constant: it does not excite the system");
  }
}

}  // namespace sysid
