#pragma once
/// @file
/// Purpose: read the manifest of a model family (DESIGN.md "Model families over
/// operating conditions"): a CSV file with a header row and one row per
/// experiment — the column `log` (a CSV log, relative to the manifest's folder),
/// an optional column `validate` (a second log of the same condition) and any
/// number of condition columns, numbers or labels.
///
/// Format: comma-separated; spaces around a field are dropped; a field may be
/// quoted ("Pos 2, left") with "" for a quote inside; blank lines and lines that
/// start with '#' are skipped. A condition column is numeric when every one of its
/// values reads as a number (then each is a JSON number in the family file), else
/// every value is a label.
///
/// Errors: sysid::DataError naming the manifest, the line and the column: no
/// `log` column, a duplicated column name, a row with another number of fields
/// than the header, an empty `log` field, no rows, a quote left open.
#include <sysid/family/mode_spread.hpp>

#include <string>
#include <vector>

namespace sysid {

struct FamilyManifestRow {
  std::string log;       ///< as written in the manifest
  std::string validate;  ///< as written; empty when none
  std::string log_path, validate_path;  ///< resolved against the manifest's folder
  long line = 0;         ///< 1-based line in the manifest
};

struct FamilyManifest {
  std::string path;
  std::vector<FamilyManifestRow> rows;
  std::vector<Condition> conditions;  ///< the condition columns, in the file's order, one value per row
};

FamilyManifest read_family_manifest(const std::string& path);

}  // namespace sysid
