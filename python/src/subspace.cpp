// sysid.n4sid (and moesp, cva): subspace identification, the same call and the same
// model file as `sysid n4sid` (io/n4sid_model_file.hpp).
#include <sysid/io/n4sid_model_file.hpp>
#include <sysid/subspace/n4sid.hpp>

#include <nanobind/stl/pair.h>
#include <nanobind/stl/variant.h>

#include <chrono>
#include <variant>

#include "bindings.hpp"

namespace sysid::python {

namespace {

/// order: a number, or "auto" / None for the order rule's choice.
int order_from(const std::variant<int, std::string, nb::none>& order) {
  if (const int* n = std::get_if<int>(&order)) {
    if (*n < 1) throw std::invalid_argument("order: expected a number >= 1 or 'auto', found " + std::to_string(*n));
    return *n;
  }
  if (const std::string* s = std::get_if<std::string>(&order); s && *s != "auto")
    throw std::invalid_argument("order: expected a number >= 1 or 'auto', found '" + *s + "'");
  return 0;
}

ModelFile identify_subspace(const std::optional<SampleArray>& u, const SampleArray& y, double Ts,
                            const std::variant<int, std::string, nb::none>& order, const std::string& method,
                            std::optional<int> horizon, std::optional<int> max_order, const std::string& order_rule,
                            bool enforce_stability, bool allow_unstable, std::optional<double> band_limit_hz,
                            int band_limit_order, std::optional<int> decimation, const std::string& hankel,
                            const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
                            const std::string& refine) {
  if (!u) throw std::invalid_argument("n4sid: needs the inputs u (an AR or ARMA model describes a time series)");
  N4sidOptions options;
  options.weighting = subspace_weighting_from_name(method);
  options.order = order_from(order);
  if (max_order) options.max_order = *max_order;
  options.order_rule = order_rule_from_name(order_rule);
  if (horizon) options.horizon = *horizon;
  options.enforce_stability = enforce_stability;
  options.allow_unstable = allow_unstable;
  options.refine_poles = pole_refinement_mode_from_name(refine);
  if (band_limit_hz) {
    if (!(*band_limit_hz > 0.0)) throw std::invalid_argument("band_limit_hz: expected a frequency > 0");
    options.band_limit_hz = *band_limit_hz;
  }
  options.band_limit_order = band_limit_order;
  if (decimation) options.decimation = *decimation;
  options.route = hankel_route_from_name(hankel);
  IoData data = io_data(u, y, Ts, inputs, outputs);
  const std::vector<std::string> input_names = data.input_names, output_names = data.output_names;
  ModelFile file;
  std::vector<std::string> warnings;
  {
    nb::gil_scoped_release release;
    N4sidResult result = n4sid(std::move(data), options);
    file = n4sid_model_file(result, options, input_names, output_names);
    warnings = std::move(result.warnings);
  }
  issue_warnings(warnings);
  return file;
}

/// One column of the diagram (a physical mode or a noise column) as a dict.
nb::dict column_dict(const PhysicalMode& m) {
  nb::dict d;
  d["freq_hz"] = m.freq_hz;
  d["damping"] = m.damping;
  d["freq_spread"] = m.freq_spread;
  d["damping_spread"] = m.damping_spread;
  d["first_order"] = m.first_order;
  d["stable_poles"] = m.stable_poles;
  d["level_ratio"] = m.level_ratio;
  d["shape_collinearity"] = m.shape_collinearity;
  d["shape"] = m.shape.size() > 0 ? nb::cast(Eigen::VectorXcd(m.shape)) : nb::none();
  if (!m.noise_reason.empty()) d["reason"] = m.noise_reason;
  return d;
}

/// The stabilisation diagram as `sysid n4sid --order LO:HI --stabilization` makes
/// it, and the model of the order its rule chooses (the very model file).
std::pair<nb::dict, ModelFile> stabilization(const std::optional<SampleArray>& u, const SampleArray& y, double Ts,
                                             std::pair<int, int> orders, const std::string& method,
                                             std::optional<int> horizon, double min_level_ratio, double noise_shape_level,
                                             const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  if (!u) throw std::invalid_argument("stabilization_diagram: needs the inputs u");
  if (orders.first < 1 || orders.second <= orders.first)
    throw std::invalid_argument("orders: expected (lo, hi) with 1 <= lo < hi, found (" + std::to_string(orders.first) + ", " +
                                std::to_string(orders.second) + ")");
  if (!(min_level_ratio >= 0.0)) throw std::invalid_argument("min_level_ratio: expected a number >= 0 (0: no level test)");
  if (!(noise_shape_level >= 0.0 && noise_shape_level <= 0.5))
    throw std::invalid_argument("noise_shape_level: expected a level in [0, 0.5] (0: no shape test)");
  N4sidOptions options;
  options.weighting = subspace_weighting_from_name(method);
  if (horizon) options.horizon = *horizon;
  options.order = 0;
  options.order_rule = OrderRule::stabilization;
  options.stabilization_order_lo = orders.first;
  options.stabilization_order_hi = orders.second;
  options.stabilization.min_level_ratio = min_level_ratio;
  options.stabilization.random_shape_level = noise_shape_level;
  IoData data = io_data(u, y, Ts, inputs, outputs);
  const std::vector<std::string> input_names = data.input_names, output_names = data.output_names;
  N4sidResult result;
  ModelFile file;
  {
    nb::gil_scoped_release release;
    result = n4sid(std::move(data), options);
    file = n4sid_model_file(result, options, input_names, output_names);
  }
  issue_warnings(result.warnings);
  const StabilizationDiagram& d = result.stabilization;
  const auto count = static_cast<Eigen::Index>(d.poles.size());
  Eigen::VectorXi order(count), mode(count);
  Eigen::VectorXd freq(count), damping(count), level(count);
  Eigen::Matrix<bool, Eigen::Dynamic, 1> stable_frequency(count), stable_damping(count), stable_shape(count);
  for (Eigen::Index k = 0; k < count; ++k) {
    const StabilizationPole& p = d.poles[static_cast<std::size_t>(k)];
    order(k) = p.order;
    freq(k) = p.freq_hz;
    damping(k) = p.damping;
    level(k) = p.level;
    stable_frequency(k) = p.stable_frequency;
    stable_damping(k) = p.stable_damping;
    stable_shape(k) = p.stable_shape;
    mode(k) = p.mode + 1;  // as in the command line's CSV: 0 = in no mode's column
  }
  nb::dict poles;
  poles["order"] = order;
  poles["freq_hz"] = freq;
  poles["damping"] = damping;
  poles["level"] = level;
  poles["stable_frequency"] = stable_frequency;
  poles["stable_damping"] = stable_damping;
  poles["stable_shape"] = stable_shape;
  poles["mode"] = mode;
  nb::list modes, noise;
  for (const PhysicalMode& m : d.modes) modes.append(column_dict(m));
  for (const PhysicalMode& m : d.noise_columns) noise.append(column_dict(m));
  nb::dict out;
  out["order_lo"] = d.order_lo;
  out["order_hi"] = d.order_hi;
  out["horizon"] = result.horizon;
  out["chosen_order"] = d.chosen_order;
  out["rule"] = d.rule;
  out["criteria"] = d.criteria();
  out["with_shapes"] = d.with_shapes;
  out["poles"] = poles;
  out["modes"] = modes;
  out["noise_columns"] = noise;
  out["table"] = d.modes_table() + d.noise_columns_table();
  return {out, file};
}

/// Benchmark hook (bench/python_bench.py): the seconds of each of `repeats` calls
/// of the C++ n4sid on the same data and options as sysid.n4sid, the data already
/// in an IoData (a C++ caller's starting point), so the Python call's overhead can
/// be measured in one process against the same library build.
std::vector<double> time_n4sid(const SampleArray& u, const SampleArray& y, double Ts, int order, int horizon,
                               const std::string& method, int repeats) {
  N4sidOptions options;
  options.weighting = subspace_weighting_from_name(method);
  options.order = order;
  options.horizon = horizon;
  const IoData data = io_data(u, y, Ts, {}, {});
  std::vector<double> seconds;
  nb::gil_scoped_release release;
  for (int r = 0; r < repeats; ++r) {
    IoData copy = data;  // n4sid takes its data by value; the copy is not timed
    const auto start = std::chrono::steady_clock::now();
    const N4sidResult result = n4sid(std::move(copy), options);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return seconds;
}

}  // namespace

void bind_subspace(nb::module_& m) {
  m.def("n4sid", &identify_subspace, nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(),
        nb::arg("order") = nb::none(), nb::arg("method") = "n4sid", nb::arg("horizon") = nb::none(),
        nb::arg("max_order") = nb::none(), nb::arg("order_rule") = to_string(N4sidOptions{}.order_rule),
        nb::arg("enforce_stability") = false, nb::arg("allow_unstable") = false, nb::arg("band_limit_hz") = nb::none(),
        nb::arg("band_limit_order") = N4sidOptions{}.band_limit_order, nb::arg("decimation") = nb::none(),
        nb::arg("hankel") = "auto", nb::arg("inputs") = std::vector<std::string>{},
        nb::arg("outputs") = std::vector<std::string>{}, nb::arg("refine") = "auto",
        "Subspace identification of a state-space model in innovation form from one record.\n\n"
        "u: samples x inputs (1-D for one input); y: samples x outputs; Ts: sample time [s].\n"
        "order: a number, or None/'auto' for the order_rule's choice (at most max_order).\n"
        "method: 'n4sid', 'moesp' or 'cva' (the weighting). horizon: block rows (None: automatic,\n"
        "long enough for the slowest mode). enforce_stability: A from the zero-padded shift (always stable).\n"
        "allow_unstable: keep an unstable least-squares A. band_limit_hz: low-pass the data and put the\n"
        "filter in series with the model (the Par2 remedy). decimation: None (automatic), 1 (none) or a factor.\n"
        "hankel: 'auto', 'qr', 'cholesky', 'cholesky_double_double'. inputs/outputs: channel names.\n"
        "refine: 'auto' (re-estimate the poles on the simulation error when a given horizon differs from the\n"
        "automatic one), 'always' or 'never'; provenance['pole_refinement'] says what it did.\n"
        "Returns a Model with K, x0, offsets and provenance (order rule, horizon, fit, singular values ...),\n"
        "the very model file `sysid n4sid` writes for the same data and options. Warnings (for example a\n"
        "poorly excited band) are issued as RuntimeWarning.");
  m.def("stabilization_diagram", &stabilization, nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(), nb::arg("orders"),
        nb::arg("method") = "n4sid", nb::arg("horizon") = nb::none(),
        nb::arg("min_level_ratio") = StabilizationOptions{}.min_level_ratio,
        nb::arg("noise_shape_level") = StabilizationOptions{}.random_shape_level, nb::arg("inputs") = std::vector<std::string>{},
        nb::arg("outputs") = std::vector<std::string>{},
        "The stabilisation diagram of the model orders orders=(lo, hi) from one subspace compression, as\n"
        "`sysid n4sid --order LO:HI --stabilization FILE` makes it, and the model of the order its rule chooses.\n\n"
        "Every pole is marked stable in frequency (1 %), damping (5 %) and, with several outputs, mode shape\n"
        "(MAC >= 0.98) against the order below; the physical modes are the columns of stable poles that stand\n"
        "above the noise: level (the singular values weighted by the pole's eigenvector) at least min_level_ratio\n"
        "times that of the poles that wander at the same orders (0: no test) and, with many outputs, shapes more\n"
        "collinear than random noise's at noise_shape_level (0: no test). Returns (diagram, model): diagram is a\n"
        "dict with 'poles' (NumPy arrays order, freq_hz, damping, level, stable_frequency, stable_damping,\n"
        "stable_shape, mode: 1-based column, 0 none), 'modes' and 'noise_columns' (dicts: freq_hz, damping, spreads,\n"
        "first_order, stable_poles, level_ratio, shape_collinearity, shape; noise columns a 'reason'),\n"
        "'chosen_order', 'rule', 'criteria', 'horizon', 'table'; model is the command line's model file.\n"
        "Raises sysid.NumericalError when no column stands above the noise.");
  m.def("_time_n4sid", &time_n4sid, nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::arg("order"), nb::arg("horizon"),
        nb::arg("method"), nb::arg("repeats"),
        "Benchmark hook: seconds of each C++ n4sid call on the same data (bench/python_bench.py).");
}

}  // namespace sysid::python
