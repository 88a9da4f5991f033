#include "sysid/io/mat_file.hpp"

#include <matio.h>
#include <unistd.h>

#include <cctype>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <variant>
#include <memory>
#include <stdexcept>

#include "sysid/core/errors.hpp"

namespace sysid {

namespace {

struct MatCloser {
  void operator()(mat_t* mat) const { Mat_Close(mat); }
};
struct VarFreer {
  void operator()(matvar_t* var) const { Mat_VarFree(var); }
};
using MatHandle = std::unique_ptr<mat_t, MatCloser>;
using VarHandle = std::unique_ptr<matvar_t, VarFreer>;

void check_name(const std::string& name) {
  bool ok = !name.empty() && name.size() <= 63 && std::isalpha(static_cast<unsigned char>(name[0]));
  for (const char c : name) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (!ok)
    throw std::invalid_argument("MAT file: '" + name + "' is not a MATLAB variable name (a letter, then letters, digits, '_')");
}

VarHandle create_matrix(const std::string& name, const Eigen::MatrixXd& values) {
  std::size_t dims[2] = {static_cast<std::size_t>(values.rows()), static_cast<std::size_t>(values.cols())};
  // matio copies the data (opt 0); an empty matrix still needs a valid pointer.
  static double empty = 0.0;
  void* data = values.size() ? const_cast<double*>(values.data()) : &empty;
  return VarHandle(Mat_VarCreate(name.empty() ? nullptr : name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, data, 0));
}

VarHandle create_array(const std::string& name, const std::vector<std::size_t>& dims_in, const Eigen::MatrixXd& values) {
  std::vector<std::size_t> dims = dims_in;
  static double empty = 0.0;
  void* data = values.size() ? const_cast<double*>(values.data()) : &empty;
  return VarHandle(Mat_VarCreate(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, static_cast<int>(dims.size()), dims.data(), data, 0));
}

VarHandle create_text(const char* name, const std::string& text) {
  std::size_t text_dims[2] = {1, text.size()};
  static char empty = 0;
  void* data = text.empty() ? &empty : const_cast<char*>(text.data());
  return VarHandle(Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UTF8, 2, text_dims, data, 0));
}

VarHandle create_cell(const std::string& name, const MatVariable& v) {
  std::size_t dims[2] = {v.cell_rows, v.cell_cols};
  VarHandle cell(Mat_VarCreate(name.c_str(), MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0));
  if (!cell) return cell;
  for (std::size_t k = 0; k < v.cell.size(); ++k) {
    const MatCellElement& e = v.cell[k];
    VarHandle element = e.is_text ? create_text(nullptr, e.text) : create_matrix("", e.values);
    if (!element) return VarHandle();
    Mat_VarSetCell(cell.get(), static_cast<int>(k), element.release());  // the cell owns it from here
  }
  return cell;
}

VarHandle create_strings(const std::string& name, const std::vector<std::string>& strings) {
  std::size_t dims[2] = {strings.size(), 1};
  VarHandle cell(Mat_VarCreate(name.c_str(), MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0));
  if (!cell) return cell;
  for (std::size_t k = 0; k < strings.size(); ++k) {
    VarHandle element = create_text(nullptr, strings[k]);
    if (!element) return VarHandle();
    Mat_VarSetCell(cell.get(), static_cast<int>(k), element.release());  // the cell owns it from here
  }
  return cell;
}

std::string char_array(const matvar_t* var) {
  if (var == nullptr || var->class_type != MAT_C_CHAR || var->data == nullptr) return {};
  std::size_t count = 1;
  for (int d = 0; d < var->rank; ++d) count *= var->dims[d];
  std::string text;
  if (var->data_type == MAT_T_UINT16 || var->data_type == MAT_T_UTF16) {
    // UTF-16 as MATLAB writes it; sysid's names are ASCII, others become '?'.
    const auto* units = static_cast<const std::uint16_t*>(var->data);
    for (std::size_t k = 0; k < count; ++k) text.push_back(units[k] < 128 ? static_cast<char>(units[k]) : '?');
  } else {
    text.assign(static_cast<const char*>(var->data), count);
  }
  return text;
}

}  // namespace

void write_mat_file(const std::string& path, const std::vector<MatVariable>& variables) {
  for (const MatVariable& v : variables) check_name(v.name);
  const std::string temporary = path + ".partial-" + std::to_string(::getpid());
  {
    MatHandle mat(Mat_CreateVer(temporary.c_str(), nullptr, MAT_FT_MAT5));
    if (!mat) throw DataError(path, 0, 0, "cannot create the MAT file (check the folder exists and is writable)");
    for (const MatVariable& v : variables) {
      VarHandle var = v.is_strings ? create_strings(v.name, v.strings)
                      : v.is_cell  ? create_cell(v.name, v)
                      : !v.dims.empty() ? create_array(v.name, v.dims, v.values)
                                        : create_matrix(v.name, v.values);
      if (!var || Mat_VarWrite(mat.get(), var.get(), MAT_COMPRESSION_NONE) != 0) {
        mat.reset();
        std::filesystem::remove(temporary);
        throw DataError(path, 0, 0, "cannot write the variable '" + v.name + "' (disk full?)");
      }
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::filesystem::remove(temporary);
    throw DataError(path, 0, 0, "cannot rename the written MAT file into place: " + error.message());
  }
}

std::vector<MatVariable> read_mat_file(const std::string& path) {
  MatHandle mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat) throw DataError(path, 0, 0, "cannot open as a MAT file (missing, unreadable, or not a MAT file)");
  std::vector<MatVariable> variables;
  while (VarHandle var{Mat_VarReadNext(mat.get())}) {
    if (var->rank < 2 || var->name == nullptr) continue;
    std::size_t count = 1;
    for (int d = 0; d < var->rank; ++d) count *= var->dims[d];
    const auto rows = static_cast<Eigen::Index>(var->dims[0]);
    const auto cols = rows > 0 ? static_cast<Eigen::Index>(count / var->dims[0]) : static_cast<Eigen::Index>(var->dims[1]);
    if (var->class_type == MAT_C_DOUBLE && !var->isComplex && var->data_type == MAT_T_DOUBLE) {
      MatVariable v = MatVariable::matrix(var->name, Eigen::MatrixXd(rows, cols));
      if (v.values.size() > 0) v.values = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(var->data), rows, cols);
      if (var->rank > 2) v.dims.assign(var->dims, var->dims + var->rank);
      variables.push_back(std::move(v));
    } else if (var->class_type == MAT_C_CELL && var->rank == 2) {
      std::vector<MatCellElement> elements;
      bool all_text = true;
      for (std::size_t k = 0; k < count; ++k) {
        const matvar_t* e = Mat_VarGetCell(var.get(), static_cast<int>(k));
        MatCellElement element;
        if (e != nullptr && e->class_type == MAT_C_CHAR) {
          element.is_text = true;
          element.text = char_array(e);
        } else if (e != nullptr && e->class_type == MAT_C_DOUBLE && !e->isComplex && e->rank == 2 && e->data_type == MAT_T_DOUBLE) {
          const auto er = static_cast<Eigen::Index>(e->dims[0]), ec = static_cast<Eigen::Index>(e->dims[1]);
          element.values.resize(er, ec);
          if (er * ec > 0) element.values = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(e->data), er, ec);
        }
        all_text = all_text && element.is_text;
        elements.push_back(std::move(element));
      }
      if (all_text) {
        std::vector<std::string> strings;
        for (const MatCellElement& e : elements) strings.push_back(e.text);
        variables.push_back(MatVariable::cell_of_strings(var->name, std::move(strings)));
      } else {
        variables.push_back(MatVariable::cell_array(var->name, var->dims[0], var->dims[1], std::move(elements)));
      }
    }
  }
  return variables;
}

std::vector<MatVariable> model_mat_variables(const ModelFile& file) {
  const StateSpace& s = file.model;
  std::vector<MatVariable> v = {MatVariable::matrix("A", s.A), MatVariable::matrix("B", s.B), MatVariable::matrix("C", s.C),
                                MatVariable::matrix("D", s.D), MatVariable::matrix("Ts", Eigen::MatrixXd::Constant(1, 1, s.Ts))};
  if (file.K.size() > 0) v.push_back(MatVariable::matrix("K", file.K));
  if (file.x0.size() > 0) v.push_back(MatVariable::matrix("x0", file.x0));
  if (s.inputs() > 0) v.push_back(MatVariable::cell_of_strings("InputName", s.input_names_or_defaults()));
  v.push_back(MatVariable::cell_of_strings("OutputName", s.output_names_or_defaults()));
  return v;
}

}  // namespace sysid

namespace sysid {

MatVariable MatVariable::pages(std::string name, const std::vector<Eigen::MatrixXd>& slices) {
  const Eigen::Index rows = slices.empty() ? 0 : slices.front().rows(), cols = slices.empty() ? 0 : slices.front().cols();
  Eigen::MatrixXd values(rows, cols * static_cast<Eigen::Index>(slices.size()));
  for (std::size_t k = 0; k < slices.size(); ++k) {
    if (slices[k].rows() != rows || slices[k].cols() != cols)
      throw std::invalid_argument("MAT file: the pages of '" + name + "' differ in size");
    values.middleCols(static_cast<Eigen::Index>(k) * cols, cols) = slices[k];
  }
  MatVariable v = matrix(std::move(name), std::move(values));
  v.dims = {static_cast<std::size_t>(rows), static_cast<std::size_t>(cols), slices.size()};
  return v;
}

std::vector<MatVariable> family_mat_variables(const FamilyFile& family) {
  std::vector<MatVariable> v = model_mat_variables(family.nominal_model);
  const std::size_t n = family.members.size();
  // Members: one N-D array per matrix when every member has one order (ss() then
  // makes a model array), else cell arrays.
  bool one_order = true;
  for (const FamilyFileMember& m : family.members) one_order = one_order && m.model.model.order() == family.members.front().model.model.order();
  const char* names[4] = {"A_members", "B_members", "C_members", "D_members"};
  for (int which = 0; which < 4; ++which) {
    std::vector<Eigen::MatrixXd> slices;
    for (const FamilyFileMember& m : family.members) {
      const StateSpace& s = m.model.model;
      slices.push_back(which == 0 ? s.A : which == 1 ? s.B : which == 2 ? s.C : s.D);
    }
    if (one_order) {
      v.push_back(MatVariable::pages(names[which], slices));
    } else {
      std::vector<MatCellElement> elements;
      for (Eigen::MatrixXd& s : slices) elements.push_back({std::move(s), {}, false});
      v.push_back(MatVariable::cell_array(names[which], n, 1, std::move(elements)));
    }
  }
  const auto add_model = [&v](const StateSpace& s, const std::string& suffix) {
    v.push_back(MatVariable::matrix("A_" + suffix, s.A));
    v.push_back(MatVariable::matrix("B_" + suffix, s.B));
    v.push_back(MatVariable::matrix("C_" + suffix, s.C));
    v.push_back(MatVariable::matrix("D_" + suffix, s.D));
  };
  add_model(family.nominal_model.model, "nominal");
  if (family.uncertainty) {
    if (family.uncertainty->weight) add_model(family.uncertainty->weight->model, "weight");
    v.push_back(MatVariable::matrix("frequency_hz", family.uncertainty->frequency_hz));
    v.push_back(MatVariable::matrix("bound", family.uncertainty->bound));
  }
  const std::size_t c = family.condition_names.size();
  std::vector<MatCellElement> conditions(n * c);
  for (std::size_t col = 0; col < c; ++col)
    for (std::size_t row = 0; row < n; ++row) {
      MatCellElement& e = conditions[col * n + row];  // column-major
      const ConditionValue& value = family.members[row].conditions[col];
      if (const double* d = std::get_if<double>(&value)) {
        e.values = Eigen::MatrixXd::Constant(1, 1, *d);
      } else {
        e.is_text = true;
        e.text = std::get<std::string>(value);
      }
    }
  v.push_back(MatVariable::cell_array("conditions", n, c, std::move(conditions)));
  v.push_back(MatVariable::cell_of_strings("condition_names", family.condition_names));
  const Eigen::Index outputs = static_cast<Eigen::Index>(family.outputs.size());
  Eigen::MatrixXd fit = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(n), outputs, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < n; ++k)
    if (family.members[k].fit_percent.size() == outputs) fit.row(static_cast<Eigen::Index>(k)) = family.members[k].fit_percent.transpose();
  v.push_back(MatVariable::matrix("fit_percent", fit));
  Eigen::MatrixXd freq(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(family.modes.size())), damping = freq;
  for (std::size_t j = 0; j < family.modes.size(); ++j) {
    freq.col(static_cast<Eigen::Index>(j)) = family.modes[j].freq_hz;
    damping.col(static_cast<Eigen::Index>(j)) = family.modes[j].damping;
  }
  v.push_back(MatVariable::matrix("mode_freq_hz", freq));
  v.push_back(MatVariable::matrix("mode_damping", damping));
  return v;
}

}  // namespace sysid
