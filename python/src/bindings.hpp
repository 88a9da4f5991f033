#pragma once
// Shared pieces of the Python bindings (DESIGN.md "Python"): how NumPy arrays
// become samples, how options and results cross, and the registration function of
// each part of the module. No algorithm lives here: every function calls the
// library, as the command line's verbs do.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/filesystem.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>
#include <nlohmann/json.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <complex>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <sysid/core/io_data.hpp>
#include <sysid/io/model_json.hpp>

namespace sysid::python {

namespace nb = nanobind;

/// File names from Python: a str or any os.PathLike (pathlib.Path).
using Path = std::filesystem::path;

/// A NumPy array of samples (rows) as given: 1-D is one channel, 2-D is samples x
/// channels, in any memory layout and any real dtype (converted to float64).
using SampleArray = nb::ndarray<const double, nb::device::cpu>;

/// A view of `a` as an N x channels matrix, without a copy (strides as NumPy keeps
/// them). `name` appears in the error ("u: expected a 1-D or 2-D array, found 3-D").
using StridedMap = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;
StridedMap sample_view(const SampleArray& a, const char* name);

/// IoData of one experiment from u (may be None: a time series) and y, sample time
/// Ts, channel names (empty: u1.., y1..). The samples are copied once: the
/// identification takes the data by value.
IoData io_data(const std::optional<SampleArray>& u, const SampleArray& y, double Ts,
               const std::vector<std::string>& inputs, const std::vector<std::string>& outputs);

/// A list of equally sized matrices (one per frequency, or per lag) as one
/// (count, rows, cols) NumPy array that owns its copy.
template <class Matrix>
nb::ndarray<nb::numpy, typename Matrix::Scalar, nb::ndim<3>> stack_matrices(const std::vector<Matrix>& matrices) {
  using Scalar = typename Matrix::Scalar;
  const std::size_t count = matrices.size();
  const std::size_t rows = count ? static_cast<std::size_t>(matrices.front().rows()) : 0;
  const std::size_t cols = count ? static_cast<std::size_t>(matrices.front().cols()) : 0;
  auto* data = new Scalar[std::max<std::size_t>(count * rows * cols, 1)];
  for (std::size_t k = 0; k < count; ++k)
    for (std::size_t i = 0; i < rows; ++i)
      for (std::size_t j = 0; j < cols; ++j)
        data[(k * rows + i) * cols + j] = matrices[k](static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
  nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<Scalar*>(p); });
  return nb::ndarray<nb::numpy, Scalar, nb::ndim<3>>(data, {count, rows, cols}, owner);
}

/// nlohmann::json <-> Python objects (dict, list, float, int, str, bool, None),
/// through the json module so that numbers keep their exact value.
nb::object to_python(const nlohmann::json& value);
nlohmann::json from_python(const nb::handle& value);

/// The library's warnings (a poorly excited band, an order decision on a weak
/// gap ...) as Python RuntimeWarnings, so `warnings` filters and pytest see them.
/// Call with the GIL held.
void issue_warnings(const std::vector<std::string>& warnings);

void bind_errors(nb::module_& m);
void bind_model(nb::module_& m);
void bind_data(nb::module_& m);
void bind_subspace(nb::module_& m);
void bind_polynomial(nb::module_& m);
void bind_realization(nb::module_& m);
void bind_adaptive(nb::module_& m);
void bind_reduce(nb::module_& m);
void bind_spectral(nb::module_& m);
void bind_signal(nb::module_& m);
void bind_validate(nb::module_& m);
void bind_diagnose(nb::module_& m);
void bind_fem(nb::module_& m);
void bind_family(nb::module_& m);

}  // namespace sysid::python
