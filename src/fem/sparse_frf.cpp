// Sparse direct frequency response of FE models with UMFPACK (see sparse_frf.hpp).
#include "sysid/fem/sparse_frf.hpp"

#include <umfpack.h>

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "sysid/core/errors.hpp"
#include "sysid/core/format_number.hpp"
#include "fem/detail/krylov_sweep.hpp"

namespace sysid::fem {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using Complex = std::complex<double>;

/// The values of `a` on the (superset) pattern `pattern`, both compressed with
/// sorted inner indices: a merge per column, O(nnz).
Eigen::VectorXd values_on_pattern(const SparseMatrix& pattern, const SparseMatrix& a) {
  Eigen::VectorXd values = Eigen::VectorXd::Zero(pattern.nonZeros());
  const int* outer = pattern.outerIndexPtr();
  const int* inner = pattern.innerIndexPtr();
  for (Eigen::Index col = 0; col < a.outerSize(); ++col) {
    int pos = outer[col];
    const int end = outer[col + 1];
    for (SparseMatrix::InnerIterator q(a, col); q; ++q) {
      while (pos < end && inner[pos] < q.row()) ++pos;
      if (pos == end || inner[pos] != q.row())
        throw std::logic_error("sparse_frf: an entry of K, M or C lies outside their union pattern");
      values(pos) += q.value();
    }
  }
  return values;
}

/// Z(omega) = K - omega^2 M + j (omega C + eta K) on the union pattern of K, M and
/// C (C the effective damping matrix, eta = 2 zeta for a modal ratio): every
/// Z(omega) has that pattern, and its values are O(nnz) from three aligned arrays.
struct DynamicStiffness {
  SparseMatrix damping;  ///< C itself, for the from-scratch assembly
  SparseMatrix pattern;
  Eigen::VectorXd k, m, c;
  double loss_factor = 0.0;

  explicit DynamicStiffness(const SecondOrderModel& model)
      : damping(model.effective_damping_matrix()), loss_factor(model.structural_loss_factor()) {
    pattern = model.stiffness.cwiseAbs() + model.mass.cwiseAbs() + damping.cwiseAbs();
    pattern.makeCompressed();
    k = values_on_pattern(pattern, model.stiffness);
    m = values_on_pattern(pattern, model.mass);
    c = values_on_pattern(pattern, damping);
  }
  Complex value(Eigen::Index q, double omega) const {
    return {k(q) - omega * omega * m(q), omega * c(q) + loss_factor * k(q)};
  }
};

/// Owner of UMFPACK's symbolic and numeric objects (freed on every path).
struct UmfpackFactors {
  void* symbolic = nullptr;
  void* numeric = nullptr;
  ~UmfpackFactors() {
    free_numeric();
    if (symbolic != nullptr) umfpack_zi_free_symbolic(&symbolic);
  }
  void free_numeric() {
    if (numeric != nullptr) umfpack_zi_free_numeric(&numeric);
  }
  void free_symbolic() {
    if (symbolic != nullptr) umfpack_zi_free_symbolic(&symbolic);
  }
};

std::string umfpack_failure(const char* stage, int status, double f_hz) {
  std::ostringstream s;
  s << "sparse_frf: UMFPACK " << stage << " failed with status " << status << " at " << f_hz << " Hz"
    << (status == UMFPACK_ERROR_out_of_memory ? " (out of memory)" : "");
  return s.str();
}

/// A complex matrix on a fixed pattern, values interleaved (re, im) as UMFPACK's
/// packed-complex form expects.
struct ComplexPattern {
  std::vector<int> outer, inner;
  std::vector<double> values;
};

ComplexPattern pattern_of(const Eigen::SparseMatrix<Complex>& z) {
  ComplexPattern p;
  p.outer.assign(z.outerIndexPtr(), z.outerIndexPtr() + z.outerSize() + 1);
  p.inner.assign(z.innerIndexPtr(), z.innerIndexPtr() + z.nonZeros());
  p.values.resize(2 * static_cast<std::size_t>(z.nonZeros()));
  for (Eigen::Index k = 0; k < z.nonZeros(); ++k) {
    p.values[2 * static_cast<std::size_t>(k)] = z.valuePtr()[k].real();
    p.values[2 * static_cast<std::size_t>(k) + 1] = z.valuePtr()[k].imag();
  }
  return p;
}

/// H at angular frequency w from the displacements at the output DOFs per unit
/// force (outputs x inputs): the quantity factor of each output.
void set_response(const SecondOrderModel& model, double w, const Eigen::MatrixXcd& at_outputs, Eigen::MatrixXcd& h) {
  for (Eigen::Index i = 0; i < at_outputs.rows(); ++i)
    h.row(i) = quantity_factor(model.outputs[static_cast<std::size_t>(i)].quantity, w) * at_outputs.row(i);
}

/// UMFPACK solves at the frequencies freq_hz(which[...]): H, the counters, rcond;
/// singular frequencies get NaN and are appended to `singular_hz`.
void direct_solves(const SecondOrderModel& model, const Eigen::VectorXd& freq_hz, const std::vector<Eigen::Index>& which,
                   const SparseFrfOptions& options, SparseFrfResult& r, std::vector<double>& singular_hz) {
  if (which.empty()) return;
  const Eigen::Index n = model.dofs(), m = static_cast<Eigen::Index>(model.inputs.size()),
                     l = static_cast<Eigen::Index>(model.outputs.size());
  const DynamicStiffness dynamic(model);
  const double eta = dynamic.loss_factor;
  ComplexPattern z = pattern_of(dynamic.pattern.cast<Complex>());
  const auto nnz = static_cast<std::size_t>(dynamic.pattern.nonZeros());

  double control[UMFPACK_CONTROL], info[UMFPACK_INFO];
  umfpack_zi_defaults(control);
  // No iterative refinement: UMFPACK's LU with its default pivoting is backward
  // stable here (measured backward error <= 2.2e-16 on a 50 000-DOF beam and a 2D
  // mesh, bench/README.md), and refinement costs about 30 % of each frequency.
  // The modal-sum and dense-solve tests (1e-8, 1e-9) guard the accuracy.
  control[UMFPACK_IRSTEP] = 0;
  UmfpackFactors factors;
  std::vector<double> rhs(2 * static_cast<std::size_t>(n), 0.0), x(2 * static_cast<std::size_t>(n), 0.0);
  Eigen::MatrixXcd at_outputs(l, m);

  for (const Eigen::Index k : which) {
    const double w = 2.0 * std::numbers::pi * freq_hz(k);
    if (options.reuse_symbolic) {
      for (std::size_t q = 0; q < nnz; ++q) {
        const Complex value = dynamic.value(static_cast<Eigen::Index>(q), w);
        z.values[2 * q] = value.real();
        z.values[2 * q + 1] = value.imag();
      }
    } else {
      // From scratch: assemble Z with sparse sums and analyse its pattern anew.
      const Eigen::SparseMatrix<Complex> zk = model.stiffness.cast<Complex>() * Complex(1.0, eta) -
                                              (w * w) * model.mass.cast<Complex>() + Complex(0.0, w) * dynamic.damping.cast<Complex>();
      z = pattern_of(zk);
      factors.free_symbolic();
    }
    if (factors.symbolic == nullptr) {
      const int status = umfpack_zi_symbolic(static_cast<int>(n), static_cast<int>(n), z.outer.data(), z.inner.data(),
                                             z.values.data(), nullptr, &factors.symbolic, control, info);
      if (status != UMFPACK_OK) throw NumericalError(umfpack_failure("symbolic analysis", status, freq_hz(k)));
      ++r.symbolic_factorisations;
    }
    factors.free_numeric();
    const int status = umfpack_zi_numeric(z.outer.data(), z.inner.data(), z.values.data(), nullptr, factors.symbolic,
                                          &factors.numeric, control, info);
    ++r.numeric_factorisations;
    ++r.direct_frequencies;
    if (status != UMFPACK_OK && status != UMFPACK_WARNING_singular_matrix)
      throw NumericalError(umfpack_failure("numeric factorisation", status, freq_hz(k)));
    const double rcond = info[UMFPACK_RCOND];
    if (rcond < r.min_rcond) {
      r.min_rcond = rcond;
      r.min_rcond_freq_hz = freq_hz(k);
    }
    Eigen::MatrixXcd& h = r.H[static_cast<std::size_t>(k)];
    if (status == UMFPACK_WARNING_singular_matrix || !(rcond >= options.singular_rcond)) {
      h.setConstant(Complex(std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()));
      singular_hz.push_back(freq_hz(k));
      continue;
    }
    for (Eigen::Index j = 0; j < m; ++j) {
      const auto dof = static_cast<std::size_t>(model.inputs[static_cast<std::size_t>(j)].dof);
      rhs[2 * dof] = 1.0;
      const int solved = umfpack_zi_solve(UMFPACK_A, z.outer.data(), z.inner.data(), z.values.data(), nullptr, x.data(),
                                          nullptr, rhs.data(), nullptr, factors.numeric, control, info);
      rhs[2 * dof] = 0.0;
      if (solved != UMFPACK_OK) throw NumericalError(umfpack_failure("solve", solved, freq_hz(k)));
      for (Eigen::Index i = 0; i < l; ++i) {
        const auto d = static_cast<std::size_t>(model.outputs[static_cast<std::size_t>(i)].dof);
        at_outputs(i, j) = Complex(x[2 * d], x[2 * d + 1]);
      }
    }
    set_response(model, w, at_outputs, h);
  }
}

/// The method `options` ask for, automatic resolved (header).
SparseFrfMethod resolve_method(const SecondOrderModel& model, const Eigen::VectorXd& freq_hz, const SparseFrfOptions& options) {
  if (options.method != SparseFrfMethod::automatic) return options.method;
  const bool proportional = model.damping.kind != DampingKind::matrix;
  return proportional && freq_hz.size() >= 50 && model.dofs() >= 2000 ? SparseFrfMethod::krylov : SparseFrfMethod::direct;
}

}  // namespace

const char* sparse_frf_method_name(SparseFrfMethod method) {
  switch (method) {
    case SparseFrfMethod::direct: return "direct";
    case SparseFrfMethod::krylov: return "krylov";
    case SparseFrfMethod::automatic: break;
  }
  return "automatic";
}

SparseFrfMethod sparse_frf_method_from_name(const std::string& name) {
  for (const SparseFrfMethod method : {SparseFrfMethod::automatic, SparseFrfMethod::direct, SparseFrfMethod::krylov})
    if (name == sparse_frf_method_name(method)) return method;
  throw std::invalid_argument("unknown sparse FRF method '" + name + "' (expected automatic, direct or krylov)");
}

SparseFrfResult sparse_frf(const SecondOrderModel& model, const Eigen::VectorXd& freq_hz, const SparseFrfOptions& options) {
  model.validate();
  for (Eigen::Index k = 0; k < freq_hz.size(); ++k)
    if (!std::isfinite(freq_hz(k)) || freq_hz(k) < 0.0)
      throw std::invalid_argument("sparse_frf: frequencies must be finite and >= 0 (entry " + std::to_string(k) + ")");
  if (!(options.krylov_tolerance > 0.0) || options.krylov_max_basis < 1 || !(options.krylov_shift_hz >= 0.0))
    throw std::invalid_argument("sparse_frf: need krylov_tolerance > 0, krylov_max_basis >= 1, krylov_shift_hz >= 0");

  const Eigen::Index m = static_cast<Eigen::Index>(model.inputs.size()), l = static_cast<Eigen::Index>(model.outputs.size());
  SparseFrfResult r;
  r.freq_hz = freq_hz;
  r.H.assign(static_cast<std::size_t>(freq_hz.size()), Eigen::MatrixXcd::Zero(l, m));
  for (const auto& in : model.inputs) r.input_names.push_back(in.name);
  for (const auto& out : model.outputs) r.output_names.push_back(out.name);
  r.min_rcond = std::numeric_limits<double>::infinity();
  r.method = resolve_method(model, freq_hz, options);

  // Modal damping ratio as structural damping: K (1 + j eta), eta = 2 zeta (header).
  if (model.structural_loss_factor() > 0.0)
    r.warnings.push_back("modal damping ratio " + format_number(model.damping.ratio) +
                         " applied as structural damping K (1 + 2j zeta) in the frequency-domain solve: exact at each resonance, "
                         "not viscous away from it");

  std::vector<Eigen::Index> direct;
  if (r.method == SparseFrfMethod::krylov) {
    const detail::KrylovSweepOptions ko{.tolerance = options.krylov_tolerance,
                                        .max_basis = options.krylov_max_basis,
                                        .shift_hz = options.krylov_shift_hz};
    const detail::KrylovSweepResult sweep = detail::krylov_sweep(model, 2.0 * std::numbers::pi * freq_hz, ko);
    r.symbolic_factorisations += sweep.symbolic_analyses;
    r.numeric_factorisations += sweep.numeric_factorisations;
    r.krylov_basis_size = sweep.basis_size;
    r.krylov_frequencies = sweep.certified;
    r.krylov_max_estimated_error = sweep.max_estimated_error;
    for (Eigen::Index k = 0; k < freq_hz.size(); ++k) {
      const Eigen::MatrixXcd& at_outputs = sweep.output_displacement[static_cast<std::size_t>(k)];
      if (at_outputs.size() == 0) direct.push_back(k);
      else set_response(model, 2.0 * std::numbers::pi * freq_hz(k), at_outputs, r.H[static_cast<std::size_t>(k)]);
    }
    r.krylov_rounding_error = sweep.rounding_error_estimate;
    if (!(sweep.rounding_error_estimate <= options.krylov_tolerance)) {
      std::ostringstream s;
      s << "the stiffness is too ill-conditioned for the Krylov sweep (round-off floor eps cond(K - sigma0 M) = "
        << sweep.rounding_error_estimate << " > tolerance " << options.krylov_tolerance
        << "): every frequency was solved directly, whose relative errors can reach the same order";
      r.warnings.push_back(s.str());
    } else if (!direct.empty()) {
      std::ostringstream s;
      s << direct.size() << " of " << freq_hz.size() << " frequencies were not certified by the Krylov basis ("
        << sweep.basis_size << " columns, relative error tolerance " << options.krylov_tolerance
        << ") and were solved directly, the first at " << freq_hz(direct.front()) << " Hz";
      r.warnings.push_back(s.str());
    }
  } else {
    for (Eigen::Index k = 0; k < freq_hz.size(); ++k) direct.push_back(k);
  }
  std::vector<double> singular_hz;
  direct_solves(model, freq_hz, direct, options, r, singular_hz);
  if (r.direct_frequencies == 0) r.min_rcond = r.min_rcond_freq_hz = std::numeric_limits<double>::quiet_NaN();
  if (!singular_hz.empty()) {
    std::ostringstream s;
    s << singular_hz.size() << " frequenc" << (singular_hz.size() == 1 ? "y" : "ies")
      << " where the dynamic stiffness is singular (reciprocal condition < " << options.singular_rcond
      << "; a rigid-body mode at 0 Hz or an undamped resonance) got NaN, the first at " << singular_hz.front() << " Hz";
    r.warnings.push_back(s.str());
  }
  return r;
}

}  // namespace sysid::fem
