#include "sysid/io/mat_file.hpp"

#include <matio.h>
#include <unistd.h>

#include <cctype>
#include <cstdint>
#include <filesystem>
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
  return VarHandle(Mat_VarCreate(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, data, 0));
}

VarHandle create_strings(const std::string& name, const std::vector<std::string>& strings) {
  std::size_t dims[2] = {strings.size(), 1};
  VarHandle cell(Mat_VarCreate(name.c_str(), MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0));
  if (!cell) return cell;
  for (std::size_t k = 0; k < strings.size(); ++k) {
    std::size_t text_dims[2] = {1, strings[k].size()};
    static char empty = 0;
    void* text = strings[k].empty() ? &empty : const_cast<char*>(strings[k].data());
    matvar_t* element = Mat_VarCreate(nullptr, MAT_C_CHAR, MAT_T_UTF8, 2, text_dims, text, 0);
    if (element == nullptr) return VarHandle();
    Mat_VarSetCell(cell.get(), static_cast<int>(k), element);  // the cell owns it from here
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
      VarHandle var = v.is_strings ? create_strings(v.name, v.strings) : create_matrix(v.name, v.values);
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
    if (var->rank != 2 || var->name == nullptr) continue;
    const auto rows = static_cast<Eigen::Index>(var->dims[0]), cols = static_cast<Eigen::Index>(var->dims[1]);
    if (var->class_type == MAT_C_DOUBLE && !var->isComplex && var->data_type == MAT_T_DOUBLE) {
      Eigen::MatrixXd values(rows, cols);
      if (values.size() > 0) values = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(var->data), rows, cols);
      variables.push_back(MatVariable::matrix(var->name, std::move(values)));
    } else if (var->class_type == MAT_C_CELL) {
      std::vector<std::string> strings;
      for (Eigen::Index k = 0; k < rows * cols; ++k) strings.push_back(char_array(Mat_VarGetCell(var.get(), static_cast<int>(k))));
      variables.push_back(MatVariable::cell_of_strings(var->name, std::move(strings)));
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
