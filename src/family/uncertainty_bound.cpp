// Implementation of family/uncertainty_bound.hpp (method in the header).
#include <sysid/family/uncertainty_bound.hpp>
#include <sysid/core/parallel_for.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sysid {

namespace {

/// P0^+ and sigma_max(P0^+) at one frequency.
struct NominalInverse {
  Eigen::MatrixXcd pinv;
  double norm = 0.0;
};

NominalInverse nominal_inverse(const Eigen::MatrixXcd& p0) {
  const Eigen::JacobiSVD<Eigen::MatrixXcd> svd(p0, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  const double cut = s.size() > 0 ? s(0) * 1e-12 : 0.0;
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(s.size());
  NominalInverse out;
  for (Eigen::Index k = 0; k < s.size(); ++k)
    if (s(k) > cut) {
      inv(k) = 1.0 / s(k);
      out.norm = std::max(out.norm, inv(k));
    }
  out.pinv = svd.matrixV() * inv.asDiagonal() * svd.matrixU().adjoint();
  return out;
}

double sigma_max(const Eigen::MatrixXcd& m) {
  if (m.rows() == 1 || m.cols() == 1) return m.norm();
  return Eigen::JacobiSVD<Eigen::MatrixXcd>(m).singularValues()(0);
}

double deviation_with(const Eigen::MatrixXcd& p, const Eigen::MatrixXcd& p0, const NominalInverse& inv, UncertaintyForm form) {
  switch (form) {
    case UncertaintyForm::multiplicative_output: return sigma_max((p - p0) * inv.pinv);
    case UncertaintyForm::multiplicative_input: return sigma_max(inv.pinv * (p - p0));
    case UncertaintyForm::additive: return sigma_max(p - p0);
  }
  return 0.0;
}

struct BoundPair {
  Eigen::VectorXd bound, spread;
};

BoundPair bound_for_nominal(const std::vector<std::vector<Eigen::MatrixXcd>>& frf, const std::vector<Eigen::VectorXd>& sd,
                            int nominal, const UncertaintyBoundOptions& o) {
  const Eigen::Index grid = static_cast<Eigen::Index>(frf.front().size());
  BoundPair out{Eigen::VectorXd::Zero(grid), Eigen::VectorXd::Zero(grid)};
  const auto& nominal_frf = frf[static_cast<std::size_t>(nominal)];
  const Eigen::VectorXd& sd0 = sd[static_cast<std::size_t>(nominal)];
  const bool siso = nominal_frf.front().rows() == 1 && nominal_frf.front().cols() == 1;
  for (Eigen::Index k = 0; k < grid; ++k) {
    const Eigen::MatrixXcd& p0 = nominal_frf[static_cast<std::size_t>(k)];
    NominalInverse inv;
    if (o.form == UncertaintyForm::additive)
      inv.norm = 1.0;
    else if (siso)
      inv.norm = std::abs(p0(0, 0)) > 0.0 ? 1.0 / std::abs(p0(0, 0)) : 0.0;
    else
      inv = nominal_inverse(p0);
    for (std::size_t i = 0; i < frf.size(); ++i) {
      if (static_cast<int>(i) == nominal) continue;
      const Eigen::MatrixXcd& p = frf[i][static_cast<std::size_t>(k)];
      // One input and one output: every form is |p - p0| times 1 or 1/|p0|.
      const double d = siso ? std::abs(p(0, 0) - p0(0, 0)) * inv.norm : deviation_with(p, p0, inv, o.form);
      double allowance = 0.0;
      if (sd[i].size() > 0 && sd0.size() > 0) allowance = o.coverage * std::hypot(sd[i](k), sd0(k)) * inv.norm;
      out.spread(k) = std::max(out.spread(k), d);
      out.bound(k) = std::max(out.bound(k), d + allowance);
    }
  }
  return out;
}

}  // namespace

const char* to_string(UncertaintyForm form) {
  switch (form) {
    case UncertaintyForm::multiplicative_output: return "multiplicative-output";
    case UncertaintyForm::multiplicative_input: return "multiplicative-input";
    case UncertaintyForm::additive: return "additive";
  }
  return "?";
}

UncertaintyForm uncertainty_form_from_name(const std::string& name) {
  for (UncertaintyForm f : {UncertaintyForm::multiplicative_output, UncertaintyForm::multiplicative_input, UncertaintyForm::additive})
    if (name == to_string(f)) return f;
  throw std::invalid_argument("uncertainty form: expected multiplicative-output, multiplicative-input or additive, found '" +
                              name + "'");
}

Eigen::VectorXd family_frequency_grid(double band_lo_hz, double band_hi_hz, const std::vector<std::vector<ModeEstimate>>& member_modes,
                                      int points) {
  if (!(band_hi_hz > band_lo_hz) || band_lo_hz < 0.0 || points < 2)
    throw std::invalid_argument("family_frequency_grid: need 0 <= band low < band high and at least 2 points");
  const double lo = band_lo_hz > 0.0 ? band_lo_hz : band_hi_hz / 1000.0;
  // (frequency, smallest relative spacing to the point kept before it): the base
  // grid always stays; a resonance point is dropped when it falls within a quarter
  // of its mode's damping of the point before, so that a hundred members with
  // nearly one resonance add its neighbourhood once, not a hundred times.
  std::vector<std::pair<double, double>> f;
  for (int k = 0; k < points; ++k)
    f.emplace_back(lo * std::pow(band_hi_hz / lo, static_cast<double>(k) / (points - 1)), 0.0);
  for (const auto& modes : member_modes)
    for (const ModeEstimate& m : modes) {
      const double zeta = std::max(m.damping, 1e-3);
      for (int k = -6; k <= 6; ++k) {
        const double x = m.freq_hz * (1.0 + 0.5 * k * zeta);
        if (x >= lo && x <= band_hi_hz) f.emplace_back(x, 0.25 * zeta);
      }
    }
  std::sort(f.begin(), f.end());
  std::vector<double> kept;
  for (const auto& [x, spacing] : f)
    if (kept.empty() || x > kept.back() * (1.0 + std::max(spacing, 1e-9))) kept.push_back(x);
  return Eigen::Map<const Eigen::VectorXd>(kept.data(), static_cast<Eigen::Index>(kept.size()));
}

double deviation_from_nominal(const Eigen::MatrixXcd& P, const Eigen::MatrixXcd& P0, UncertaintyForm form) {
  if (P.rows() != P0.rows() || P.cols() != P0.cols())
    throw std::invalid_argument("deviation_from_nominal: the member and the nominal differ in size");
  return deviation_with(P, P0, form == UncertaintyForm::additive ? NominalInverse{{}, 1.0} : nominal_inverse(P0), form);
}

UncertaintyBound uncertainty_bound(const std::vector<std::vector<Eigen::MatrixXcd>>& frf, const std::vector<Eigen::VectorXd>& sd,
                                   const UncertaintyBoundOptions& options) {
  const int members = static_cast<int>(frf.size());
  if (members < 1) throw std::invalid_argument("uncertainty_bound: need at least one member");
  if (sd.size() != frf.size()) throw std::invalid_argument("uncertainty_bound: one standard deviation vector per member");
  const std::size_t grid = frf.front().size();
  for (std::size_t i = 0; i < frf.size(); ++i) {
    if (frf[i].size() != grid) throw std::invalid_argument("uncertainty_bound: every member needs the same grid");
    if (sd[i].size() != 0 && static_cast<std::size_t>(sd[i].size()) != grid)
      throw std::invalid_argument("uncertainty_bound: a standard deviation vector does not match the grid");
    for (const auto& p : frf[i])
      if (p.rows() != frf[0][0].rows() || p.cols() != frf[0][0].cols())
        throw std::invalid_argument("uncertainty_bound: the members differ in inputs or outputs");
  }
  if (options.nominal_member && (*options.nominal_member < 0 || *options.nominal_member >= members))
    throw std::invalid_argument("uncertainty_bound: nominal member out of range");
  UncertaintyBound out;
  out.with_allowance = std::all_of(sd.begin(), sd.end(), [](const Eigen::VectorXd& v) { return v.size() > 0; });
  out.peak_by_nominal = Eigen::VectorXd::Constant(members, std::numeric_limits<double>::quiet_NaN());
  if (options.nominal_member) {
    out.nominal_member = *options.nominal_member;
    out.criterion = "member " + std::to_string(out.nominal_member) + ", as asked";
  } else {
    parallel_for(static_cast<std::size_t>(members), [&](std::size_t c) {
      out.peak_by_nominal(static_cast<Eigen::Index>(c)) = bound_for_nominal(frf, sd, static_cast<int>(c), options).bound.maxCoeff();
    });
    out.peak_by_nominal.minCoeff(&out.nominal_member);
    out.criterion = std::string("the member whose bound has the smallest peak over the band (") + to_string(options.form) +
                    (out.with_allowance ? ", with the estimation allowance" : "") + ")";
  }
  BoundPair b = bound_for_nominal(frf, sd, out.nominal_member, options);
  out.bound = std::move(b.bound);
  out.spread = std::move(b.spread);
  if (options.nominal_member) out.peak_by_nominal(out.nominal_member) = out.bound.maxCoeff();
  return out;
}

}  // namespace sysid
