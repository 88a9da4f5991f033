// The stabilisation diagram (see include/sysid/subspace/stabilization_diagram.hpp).
#include <sysid/subspace/stabilization_diagram.hpp>

#include <sysid/core/format_number.hpp>
#include <sysid/core/median.hpp>
#include <sysid/core/modal_phase_collinearity.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace sysid {

namespace {

/// The mode candidates of one order: oscillatory poles (Im z > 0) with a damping
/// ratio in (0, max_damping], by frequency.
std::vector<StabilizationPole> candidates_of(const OrderPoles& op, double Ts, double max_damping) {
  std::vector<StabilizationPole> out;
  for (Eigen::Index k = 0; k < op.poles.size(); ++k) {
    const std::complex<double> z = op.poles(k);
    if (!(z.imag() > 0.0) || std::abs(z) == 0.0) continue;
    const std::complex<double> s = std::log(z) / Ts;
    const double wn = std::abs(s), damping = -s.real() / wn;
    if (!(damping > 0.0 && damping <= max_damping)) continue;
    StabilizationPole p;
    p.order = op.order;
    p.freq_hz = wn / (2.0 * std::numbers::pi);
    p.damping = damping;
    if (op.levels.size() == op.poles.size()) p.level = op.levels(k);
    if (op.shapes.cols() == op.poles.size() && op.shapes.rows() > 0) {
      p.shape = op.shapes.col(k);
      const double norm = p.shape.norm();
      if (norm > 0.0) p.shape /= norm;
    }
    out.push_back(std::move(p));
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.freq_hz < b.freq_hz; });
  return out;
}

/// Marks `p` against the candidates of the order below: the nearest in frequency
/// (with shapes: the best MAC among those within the frequency tolerance).
void mark_against(StabilizationPole& p, const std::vector<StabilizationPole>& below, const StabilizationOptions& o,
                  bool with_shapes) {
  const StabilizationPole* nearest = nullptr;
  double nearest_gap = std::numeric_limits<double>::infinity(), best_mac = -1.0;
  for (const auto& q : below) {
    const double gap = std::abs(p.freq_hz - q.freq_hz) / q.freq_hz;
    if (with_shapes && gap <= o.frequency_tolerance) {
      const double mac = modal_assurance_criterion(p.shape, q.shape);
      if (mac > best_mac) {
        best_mac = mac;
        nearest = &q;
        nearest_gap = gap;
      }
    } else if (best_mac < 0.0 && gap < nearest_gap) {
      nearest = &q;
      nearest_gap = gap;
    }
  }
  if (nearest == nullptr) return;
  p.stable_frequency = nearest_gap <= o.frequency_tolerance;
  p.stable_damping = p.stable_frequency && std::abs(p.damping - nearest->damping) <= o.damping_tolerance * nearest->damping;
  p.stable_shape = p.stable_frequency && with_shapes && best_mac >= 1.0 - o.mac_tolerance;
}

/// Columns of fully stable poles (file comment), each with at most one pole per order.
std::vector<std::vector<StabilizationPole*>> stable_columns(std::vector<StabilizationPole>& poles, bool with_shapes,
                                                            const StabilizationOptions& o) {
  std::vector<StabilizationPole*> stable;
  for (auto& p : poles)
    if (p.mark(with_shapes) == 's') stable.push_back(&p);
  std::sort(stable.begin(), stable.end(), [](const auto* a, const auto* b) { return a->freq_hz < b->freq_hz; });
  std::vector<std::vector<StabilizationPole*>> columns;
  double sum = 0.0;
  for (StabilizationPole* p : stable) {
    if (!columns.empty()) {
      auto& column = columns.back();
      const double mean = sum / static_cast<double>(column.size());
      if (std::abs(p->freq_hz - mean) <= 2.0 * o.frequency_tolerance * mean) {
        // One pole per order: of two, the one nearer the column's mean stays.
        auto same = std::find_if(column.begin(), column.end(), [&](const auto* q) { return q->order == p->order; });
        if (same == column.end()) {
          column.push_back(p);
          sum += p->freq_hz;
        } else if (std::abs(p->freq_hz - mean) < std::abs((*same)->freq_hz - mean)) {
          sum += p->freq_hz - (*same)->freq_hz;
          *same = p;
        }
        continue;
      }
    }
    columns.push_back({p});
    sum = p->freq_hz;
  }
  return columns;
}

/// Whether a pole's shape, of quadrature_tolerant_collinearity `collinearity`,
/// is no more collinear than a random shape of as many effective outputs is
/// with probability `level` (header comment); false when the shape spreads over
/// too few outputs for the test to tell.
bool random_like_shape(const Eigen::VectorXcd& shape, double collinearity, double level) {
  const double outputs = shape_effective_outputs(shape);
  if (!(outputs > 1.0)) return false;
  const double quantile = random_shape_collinearity_quantile(outputs, level);
  return quantile <= 0.5 && collinearity < quantile;
}

/// The table of modes_table() for any list of columns, the first heading
/// `label`; with_reasons: each row ends with the column's noise_reason.
std::string columns_table(const std::vector<PhysicalMode>& columns, bool with_shapes, const char* label, bool with_reasons) {
  std::ostringstream s;
  char buf[200];
  std::snprintf(buf, sizeof buf, "%6s  %12s  %10s  %12s  %12s  %6s  %7s  %9s", label, "freq [Hz]", "damping", "freq spread",
                "damp spread", "from", "stable", "level");
  s << buf << (with_shapes ? "      MPC" : "") << (with_reasons ? "  why not a mode" : "") << "\n";
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const PhysicalMode& m = columns[k];
    std::snprintf(buf, sizeof buf, "%6zu  %12.6g  %10.4g  %11.3g%%  %11.3g%%  %6d  %7d  %8.3gx", k + 1, m.freq_hz, m.damping,
                  100.0 * m.freq_spread, 100.0 * m.damping_spread, m.first_order, m.stable_poles, m.level_ratio);
    s << buf;
    if (with_shapes) {
      std::snprintf(buf, sizeof buf, "  %7.3f", m.shape_collinearity);
      s << buf;
    }
    if (with_reasons) s << "  " << m.noise_reason;
    s << "\n";
  }
  return s.str();
}

/// Per order (index order - lo): the median level of the wandering poles there,
/// NaN where there are none. A wandering pole is new at its order (not stable
/// in frequency) and lies in no column's band (its frequencies widened by twice
/// the frequency tolerance): a mode's first pole, or one that drops out of its
/// column for an order, is not noise. Poles stable in frequency but not in
/// damping or shape are left out too: often modes the data hold less firmly.
std::vector<double> wandering_levels(const std::vector<StabilizationPole>& poles, int lo, int hi,
                                     const std::vector<std::vector<StabilizationPole*>>& columns, double tolerance) {
  std::vector<std::pair<double, double>> bands;
  for (const auto& column : columns) {
    const auto [low, high] = std::minmax_element(column.begin(), column.end(),
                                                 [](const auto* a, const auto* b) { return a->freq_hz < b->freq_hz; });
    bands.emplace_back((*low)->freq_hz * (1.0 - 2.0 * tolerance), (*high)->freq_hz * (1.0 + 2.0 * tolerance));
  }
  std::vector<std::vector<double>> levels(static_cast<std::size_t>(hi - lo + 1));
  for (const auto& p : poles) {
    if (p.stable_frequency || !std::isfinite(p.level)) continue;
    const bool in_band = std::any_of(bands.begin(), bands.end(),
                                     [&](const auto& b) { return p.freq_hz >= b.first && p.freq_hz <= b.second; });
    if (!in_band) levels[static_cast<std::size_t>(p.order - lo)].push_back(p.level);
  }
  std::vector<double> out;
  for (auto& l : levels) out.push_back(l.empty() ? std::numeric_limits<double>::quiet_NaN() : median(std::move(l)));
  return out;
}

/// The median of the values of the upper half of the orders (NaN for none): the
/// higher the order, the more of the wandering poles are noise, so the surer the
/// reference (below the true order they include modes not yet resolved).
double upper_orders_median(std::vector<std::pair<int, double>> by_order) {
  if (by_order.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(by_order.begin(), by_order.end());
  std::vector<double> upper;
  for (std::size_t k = by_order.size() / 2; k < by_order.size(); ++k) upper.push_back(by_order[k].second);
  return median(std::move(upper));
}

/// The order rule: the lowest order whose candidates (`poles`, by order) include
/// one within twice the frequency tolerance of every mode; 0 when none does.
int lowest_order_holding(const std::vector<StabilizationPole>& poles, const std::vector<PhysicalMode>& modes,
                         double tolerance) {
  for (auto begin = poles.begin(); begin != poles.end();) {
    const auto end = std::find_if(begin, poles.end(), [&](const StabilizationPole& p) { return p.order != begin->order; });
    const bool all = std::all_of(modes.begin(), modes.end(), [&](const PhysicalMode& m) {
      return std::any_of(begin, end, [&](const StabilizationPole& p) {
        return std::abs(p.freq_hz - m.freq_hz) <= 2.0 * tolerance * m.freq_hz;
      });
    });
    if (all) return begin->order;
    begin = end;
  }
  return 0;
}

}  // namespace

StabilizationDiagram stabilization_diagram(const std::vector<OrderPoles>& orders, double Ts, const StabilizationOptions& o) {
  if (!(Ts > 0.0)) throw std::invalid_argument("stabilization diagram: need Ts > 0");
  if (orders.empty()) throw std::invalid_argument("stabilization diagram: need at least one order");
  for (std::size_t k = 1; k < orders.size(); ++k)
    if (orders[k].order != orders[k - 1].order + 1)
      throw std::invalid_argument("stabilization diagram: need consecutive increasing orders");
  if (!(o.frequency_tolerance > 0.0 && o.damping_tolerance > 0.0 && o.mac_tolerance > 0.0 && o.max_damping > 0.0))
    throw std::invalid_argument("stabilization diagram: need positive tolerances and max_damping");
  if (!(o.random_shape_level >= 0.0 && o.random_shape_level < 1.0))
    throw std::invalid_argument("stabilization diagram: need 0 <= random_shape_level < 1");
  if (!(o.min_level_ratio >= 0.0)) throw std::invalid_argument("stabilization diagram: need min_level_ratio >= 0");
  StabilizationDiagram d;
  d.options = o;
  d.order_lo = orders.front().order;
  d.order_hi = orders.back().order;
  d.with_shapes = orders.front().shapes.rows() > 1;
  std::vector<std::vector<StabilizationPole>> by_order;
  for (const auto& op : orders) {
    if (op.levels.size() > 0 && op.levels.size() != op.poles.size())
      throw std::invalid_argument("stabilization diagram: order " + std::to_string(op.order) + " has " +
                                  std::to_string(op.levels.size()) + " levels for " + std::to_string(op.poles.size()) + " poles");
    if (op.shapes.size() > 0 && op.shapes.cols() != op.poles.size())
      throw std::invalid_argument("stabilization diagram: order " + std::to_string(op.order) + " has " +
                                  std::to_string(op.shapes.cols()) + " shapes for " + std::to_string(op.poles.size()) + " poles");
    by_order.push_back(candidates_of(op, Ts, o.max_damping));
    if (by_order.size() > 1)
      for (auto& p : by_order.back()) mark_against(p, by_order[by_order.size() - 2], o, d.with_shapes);
  }
  for (auto& order : by_order)
    for (auto& p : order) d.poles.push_back(std::move(p));

  // Physical modes: the columns that persist, above the noise.
  auto columns = stable_columns(d.poles, d.with_shapes, o);
  const std::vector<double> reference = wandering_levels(d.poles, d.order_lo, d.order_hi, columns, o.frequency_tolerance);
  struct Persistent {
    PhysicalMode mode;
    std::vector<StabilizationPole*>* column;
  };
  std::vector<Persistent> persistent;  // the columns that pass the persistence tests
  for (auto& column : columns) {
    int first = std::numeric_limits<int>::max();
    const StabilizationPole* top = nullptr;
    std::vector<double> f, z, collinearity;
    std::vector<std::pair<int, double>> level_ratios;  // (order, level / reference)
    int random_like = 0;
    for (const auto* p : column) {
      const double wandering = reference[static_cast<std::size_t>(p->order - d.order_lo)];
      if (std::isfinite(p->level) && wandering > 0.0) level_ratios.emplace_back(p->order, p->level / wandering);
      first = std::min(first, p->order);
      if (top == nullptr || p->order > top->order) top = p;
      f.push_back(p->freq_hz);
      z.push_back(p->damping);
      if (d.with_shapes) {
        collinearity.push_back(quadrature_tolerant_collinearity(p->shape));
        random_like += o.random_shape_level > 0.0 && random_like_shape(p->shape, collinearity.back(), o.random_shape_level);
      }
    }
    const int span = d.order_hi - first + 1;
    const double latest_start = d.order_lo + o.latest_column_start * (d.order_hi - d.order_lo);
    if (static_cast<int>(column.size()) < o.min_column_poles ||
        static_cast<double>(column.size()) < o.min_column_share * static_cast<double>(span) || first > latest_start)
      continue;
    PhysicalMode mode;
    mode.freq_hz = median(f);
    mode.damping = median(z);
    mode.freq_spread = (*std::max_element(f.begin(), f.end()) - *std::min_element(f.begin(), f.end())) / mode.freq_hz;
    mode.damping_spread = (*std::max_element(z.begin(), z.end()) - *std::min_element(z.begin(), z.end())) / mode.damping;
    mode.first_order = first;
    mode.stable_poles = static_cast<int>(column.size());
    if (d.with_shapes) {
      mode.shape = top->shape;
      mode.shape_collinearity = median(collinearity);
      mode.random_like_poles = random_like;
    }
    mode.level_ratio = upper_orders_median(std::move(level_ratios));
    if (2 * random_like > static_cast<int>(column.size()))
      mode.noise_reason = "shapes no more collinear than noise's (MPC " + format_number(mode.shape_collinearity, 2) + ")";
    persistent.push_back({std::move(mode), &column});
  }
  // A column at the noise's level is noise when it also first stands after
  // every clearer column has: the high orders fit it. A weak column among the
  // clear columns' orders stays (the weakest modes of the F-16 test).
  const auto weak = [&](const PhysicalMode& m) { return o.min_level_ratio > 0.0 && m.level_ratio < o.min_level_ratio; };
  int clear_from = 0;  // the order from which every clear column stands; 0: no clear column
  for (const auto& c : persistent)
    if (c.mode.noise_reason.empty() && !weak(c.mode)) clear_from = std::max(clear_from, c.mode.first_order);
  for (auto& c : persistent) {
    if (c.mode.noise_reason.empty() && weak(c.mode) && clear_from > 0 && c.mode.first_order > clear_from)
      c.mode.noise_reason = "level " + format_number(c.mode.level_ratio, 3) + " x the wandering poles' (< " +
                            format_number(o.min_level_ratio, 3) + ") from order " + std::to_string(c.mode.first_order) +
                            ", after every clearer column stands (order " + std::to_string(clear_from) + ")";
    if (!c.mode.noise_reason.empty()) {
      d.noise_columns.push_back(std::move(c.mode));
      continue;
    }
    for (auto* p : *c.column) p->mode = static_cast<int>(d.modes.size());
    d.modes.push_back(std::move(c.mode));
  }

  // The order rule: the lowest order with a candidate at every physical mode.
  if (d.modes.empty()) {
    d.rule = "stabilization diagram: no column of stable poles";
    if (!d.noise_columns.empty()) {
      d.rule += " above the noise (";
      for (std::size_t k = 0; k < d.noise_columns.size(); ++k)
        d.rule += (k > 0 ? "; " : "") + format_number(d.noise_columns[k].freq_hz, 4) + " Hz: " + d.noise_columns[k].noise_reason;
      d.rule += ")";
    }
    d.rule += " (" + d.criteria() + ")";
    return d;
  }
  d.chosen_order = lowest_order_holding(d.poles, d.modes, o.frequency_tolerance);
  std::ostringstream why;
  why << "stabilization diagram: " << d.modes.size() << " physical mode(s) stable over orders " << d.order_lo << ".." << d.order_hi;
  if (d.chosen_order > 0)
    why << ", all present from order " << d.chosen_order;
  else
    why << ", never all present in one order";
  if (!d.noise_columns.empty()) {
    why << "; " << d.noise_columns.size() << " column(s) of noise not counted (";
    for (std::size_t k = 0; k < d.noise_columns.size(); ++k)
      why << (k > 0 ? ", " : "") << format_number(d.noise_columns[k].freq_hz, 4) << " Hz";
    why << ")";
  }
  why << " (" << d.criteria() << ")";
  d.rule = why.str();
  return d;
}

std::string StabilizationDiagram::criteria() const {
  std::ostringstream s;
  s << "stable: frequency within " << format_number(100.0 * options.frequency_tolerance, 3) << " %, damping within "
    << format_number(100.0 * options.damping_tolerance, 3) << " %";
  if (with_shapes) s << ", MAC >= " << format_number(1.0 - options.mac_tolerance, 4);
  s << " of the order below; modes: damping <= " << format_number(options.max_damping, 3);
  if (options.min_level_ratio > 0.0)
    s << ", level >= " << format_number(options.min_level_ratio, 3) << " x the wandering poles'";
  if (with_shapes && options.random_shape_level > 0.0)
    s << ", shapes more collinear than noise's at the " << format_number(100.0 * options.random_shape_level, 3) << " % level";
  return s.str();
}

std::string StabilizationDiagram::modes_table() const { return columns_table(modes, with_shapes, "mode", false); }

std::string StabilizationDiagram::noise_columns_table() const {
  return noise_columns.empty() ? std::string() : columns_table(noise_columns, with_shapes, "column", true);
}

}  // namespace sysid
