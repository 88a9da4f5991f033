// sysid.read_log: a CSV log (DESIGN.md "CSV logs") as NumPy arrays, with the
// command line's parser, sample-time rules and NaN policies.
#include <sysid/io/csv.hpp>

#include <nanobind/stl/tuple.h>

#include "bindings.hpp"

namespace sysid::python {

namespace {

char layout_character(const std::optional<std::string>& text, const char* what) {
  if (!text) return 0;
  if (*text == "tab" || *text == "\t") return '\t';
  if (*text == "space" || *text == " ") return ' ';
  if (text->size() == 1) return (*text)[0];
  throw std::invalid_argument(std::string(what) + ": expected one character ('tab', 'space'), found '" + *text + "'");
}

std::tuple<Eigen::MatrixXd, Eigen::MatrixXd, double> read_log_arrays(
    const Path& path, const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
    std::optional<double> ts, const std::string& time_column, const std::string& nan_policy,
    const std::optional<std::string>& time_unit, const std::optional<std::string>& delimiter,
    const std::optional<std::string>& decimal) {
  LogOptions options;
  options.inputs = inputs;
  options.outputs = outputs;
  options.ts = ts;
  options.time_column = time_column;
  options.nan_policy = nan_policy_from_name(nan_policy);
  if (time_unit) {
    options.time_unit = time_unit_from_symbol(*time_unit);
    if (!options.time_unit) throw std::invalid_argument("time_unit: expected 's', 'ms' or 'us', found '" + *time_unit + "'");
  }
  CsvFormat format;
  format.delimiter = layout_character(delimiter, "delimiter");
  format.decimal = layout_character(decimal, "decimal");
  IoData data;
  {
    nb::gil_scoped_release release;
    data = log_from_table(read_csv(path.string(), format), options);
  }
  Experiment& e = data.experiments.front();
  return {std::move(e.u), std::move(e.y), data.Ts};
}

}  // namespace

void bind_data(nb::module_& m) {
  m.def("read_log", &read_log_arrays, nb::arg("path"), nb::arg("inputs") = std::vector<std::string>{},
        nb::arg("outputs") = std::vector<std::string>{}, nb::kw_only(), nb::arg("ts") = nb::none(),
        nb::arg("time_column") = "t", nb::arg("nan_policy") = "error", nb::arg("time_unit") = nb::none(),
        nb::arg("delimiter") = nb::none(), nb::arg("decimal") = nb::none(),
        "Read a CSV log: (u, y, Ts) with u samples x inputs, y samples x outputs, Ts in seconds.\n\n"
        "The columns are chosen by name. Ts comes from the time column (`time_column`, in the unit its name\n"
        "states or `time_unit` 's'|'ms'|'us') or from `ts`; when both are there they must agree.\n"
        "nan_policy: 'error' (default), 'drop' (leading and trailing rows), 'interpolate'.\n"
        "delimiter and decimal: detected from the file unless given (',', ';', 'tab', 'space'; '.' or ',').\n"
        "Raises sysid.DataError (a ValueError) naming file:line:column for a bad file.");
}

}  // namespace sysid::python
