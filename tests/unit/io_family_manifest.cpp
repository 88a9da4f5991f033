// Tests for sysid::read_family_manifest (include/sysid/io/family_manifest.hpp): the
// columns (log, optional validate, conditions as numbers or labels), CSV quoting,
// comments and blank lines, paths relative to the manifest's folder, and errors
// naming the manifest, the line and the column.
#include <sysid/core/errors.hpp>
#include <sysid/io/family_manifest.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include "run_cli.hpp"

namespace test_unit_io_family_manifest {

using namespace sysid;
using sysid::test::TempDir;
using sysid::test::write_text_file;

namespace {

std::string normal(const std::filesystem::path& p) { return p.lexically_normal().string(); }

double number(const ConditionValue& v) { return std::get<double>(v); }
const std::string& label(const ConditionValue& v) { return std::get<std::string>(v); }

/// The DataError of reading `text` as a manifest (fails the test when none).
DataError error_of(const TempDir& dir, const std::string& text) {
  const std::string path = dir / "bad.csv";
  write_text_file(path, text);
  try {
    read_family_manifest(path);
  } catch (const DataError& e) {
    return e;
  }
  ADD_FAILURE() << "no DataError for:\n" << text;
  return DataError("none");
}

/// The error names the manifest, the line and the column, in what() too.
void expect_at(const DataError& e, const std::string& path, long line, long column, const std::string& words) {
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), line) << e.what();
  EXPECT_EQ(e.column(), column) << e.what();
  const std::string what = e.what();
  EXPECT_NE(what.find(path + ":" + std::to_string(line) + ":" + std::to_string(column) + ": "), std::string::npos) << what;
  EXPECT_NE(what.find(words), std::string::npos) << what;
}

}  // namespace

TEST(IoFamilyManifest, NumbersLabelsQuotesCommentsAndBlankLines) {
  TempDir dir;
  const std::string path = dir / "manifest.csv";
  write_text_file(path,
                  "# the arm at four payloads\n"                              // 1
                  "\n"                                                        // 2
                  "payload_kg, side ,log,validate,level\n"                    // 3
                  "0, Pos1, runs/p0.csv, val/p0.csv,1\n"                      // 4
                  "# a comment between rows\n"                                // 5
                  "0.5,\"Pos 2, left\",runs/p05.csv,,2\n"                     // 6
                  "1e-1,\"say \"\"hi\"\"\", \"runs/a, b.csv\" ,val/x.csv,high\n"  // 7
                  "   \n"                                                     // 8
                  "2.50,Pos1,runs/p2.csv,,3\n");                              // 9
  const FamilyManifest m = read_family_manifest(path);
  EXPECT_EQ(m.path, path);
  ASSERT_EQ(m.rows.size(), 4u);
  const long lines[4] = {4, 6, 7, 9};
  const char* logs[4] = {"runs/p0.csv", "runs/p05.csv", "runs/a, b.csv", "runs/p2.csv"};
  const char* validates[4] = {"val/p0.csv", "", "val/x.csv", ""};
  for (std::size_t r = 0; r < 4; ++r) {
    EXPECT_EQ(m.rows[r].line, lines[r]) << r;
    EXPECT_EQ(m.rows[r].log, logs[r]) << r;
    EXPECT_EQ(m.rows[r].validate, validates[r]) << r;
    EXPECT_EQ(m.rows[r].log_path, normal(dir.path() / logs[r])) << r;
    EXPECT_EQ(m.rows[r].validate_path, *validates[r] ? normal(dir.path() / validates[r]) : std::string()) << r;
  }
  // Conditions in the file's order, log and validate excluded, names trimmed.
  ASSERT_EQ(m.conditions.size(), 3u);
  EXPECT_EQ(m.conditions[0].name, "payload_kg");
  EXPECT_EQ(m.conditions[1].name, "side");
  EXPECT_EQ(m.conditions[2].name, "level");
  // Every payload a number: a numeric column.
  ASSERT_TRUE(m.conditions[0].numeric());
  ASSERT_EQ(m.conditions[0].values.size(), 4u);
  EXPECT_EQ(number(m.conditions[0].values[0]), 0.0);
  EXPECT_EQ(number(m.conditions[0].values[1]), 0.5);
  EXPECT_EQ(number(m.conditions[0].values[2]), 0.1);
  EXPECT_EQ(number(m.conditions[0].values[3]), 2.5);
  // Quoted labels keep their commas and "" becomes ".
  ASSERT_FALSE(m.conditions[1].numeric());
  EXPECT_EQ(label(m.conditions[1].values[0]), "Pos1");
  EXPECT_EQ(label(m.conditions[1].values[1]), "Pos 2, left");
  EXPECT_EQ(label(m.conditions[1].values[2]), "say \"hi\"");
  EXPECT_EQ(label(m.conditions[1].values[3]), "Pos1");
  // One value that is not a number makes the whole column labels, as written.
  ASSERT_FALSE(m.conditions[2].numeric());
  EXPECT_EQ(label(m.conditions[2].values[0]), "1");
  EXPECT_EQ(label(m.conditions[2].values[2]), "high");
  EXPECT_EQ(label(m.conditions[2].values[3]), "3");
}

TEST(IoFamilyManifest, NonFiniteNumbersAndCrlfLineEnds) {
  TempDir dir;
  const std::string path = dir / "m.csv";
  // "inf" and "nan" are no condition values: the column is labels. CRLF ends are
  // not part of a field, quoted or not.
  write_text_file(path, "log,gain,temp,\"where\"\r\na.csv,inf,20,\"bay 1\"\r\nb.csv,1,21.5,\"bay 2\"\r\n");
  const FamilyManifest m = read_family_manifest(path);
  ASSERT_EQ(m.rows.size(), 2u);
  EXPECT_EQ(m.rows[1].log, "b.csv");
  ASSERT_EQ(m.conditions.size(), 3u);
  EXPECT_FALSE(m.conditions[0].numeric());
  EXPECT_EQ(label(m.conditions[0].values[0]), "inf");
  ASSERT_TRUE(m.conditions[1].numeric());
  EXPECT_EQ(number(m.conditions[1].values[1]), 21.5);
  EXPECT_EQ(m.conditions[2].name, "where");
  EXPECT_EQ(label(m.conditions[2].values[1]), "bay 2");
}

TEST(IoFamilyManifest, ValidateIsOptionalAndPathsAreRelativeToTheManifest) {
  TempDir dir;
  std::filesystem::create_directories(dir.path() / "campaign" / "day1");
  const std::string path = dir / "campaign/day1/manifest.csv";
  const std::string absolute = normal(dir.path() / "elsewhere" / "c.csv");
  write_text_file(path, "log,payload_kg\nruns/a.csv,0\n../b.csv,1\n" + absolute + ",2\n./d.csv,3\n");
  const FamilyManifest m = read_family_manifest(path);
  ASSERT_EQ(m.rows.size(), 4u);
  EXPECT_EQ(m.rows[0].log_path, normal(dir.path() / "campaign/day1/runs/a.csv"));
  EXPECT_EQ(m.rows[1].log_path, normal(dir.path() / "campaign/b.csv"));
  EXPECT_EQ(m.rows[2].log_path, absolute);
  EXPECT_EQ(m.rows[3].log_path, normal(dir.path() / "campaign/day1/d.csv"));
  EXPECT_EQ(m.rows[1].log, "../b.csv") << "the log as written";
  for (const FamilyManifestRow& row : m.rows) {
    EXPECT_TRUE(row.validate.empty());
    EXPECT_TRUE(row.validate_path.empty());
  }
  ASSERT_EQ(m.conditions.size(), 1u);
  EXPECT_TRUE(m.conditions[0].numeric());
  // Only a log column: no conditions.
  write_text_file(dir / "only_log.csv", "log\na.csv\nb.csv\n");
  const FamilyManifest only = read_family_manifest(dir / "only_log.csv");
  EXPECT_EQ(only.rows.size(), 2u);
  EXPECT_TRUE(only.conditions.empty());
}

TEST(IoFamilyManifest, ErrorsNameTheFileTheLineAndTheColumn) {
  TempDir dir;
  const std::string path = dir / "bad.csv";
  expect_at(error_of(dir, "# no log here\npayload,file\n0,a.csv\n"), path, 2, 1, "'log'");
  expect_at(error_of(dir, "log,payload, payload\na.csv,1,2\n"), path, 1, 14, "'payload' appears twice");
  expect_at(error_of(dir, "log,log\na.csv,b.csv\n"), path, 1, 5, "appears twice");
  expect_at(error_of(dir, "log,,payload\na.csv,1,2\n"), path, 1, 5, "empty column name");
  expect_at(error_of(dir, "log,payload\na.csv,1\nb.csv,2,3\n"), path, 3, 9, "expected 2 fields");
  expect_at(error_of(dir, "log,payload\n\nc.csv\n"), path, 3, 1, "found 1");
  expect_at(error_of(dir, "payload,log\n1,a.csv\n2,\n"), path, 3, 3, "'log' field is empty");
  expect_at(error_of(dir, "payload,log\n1,\"\"\n"), path, 2, 3, "'log' field is empty");
  expect_at(error_of(dir, "log,side\na.csv,\"Pos 2\n"), path, 2, 7, "not closed");
  expect_at(error_of(dir, "log,side\na.csv,\"Pos\"2\n"), path, 2, 12, "after a quoted field");
  {
    const DataError e = error_of(dir, "# only a header\nlog,payload\n\n");
    EXPECT_EQ(e.file(), path);
    EXPECT_GE(e.line(), 2);
    EXPECT_NE(std::string(e.what()).find("no experiment rows"), std::string::npos) << e.what();
  }
  {
    const DataError e = error_of(dir, "# nothing but a comment\n\n");
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find("empty"), std::string::npos) << e.what();
  }
  try {
    read_family_manifest(dir / "missing.csv");
    ADD_FAILURE() << "read a missing manifest";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.csv"), std::string::npos) << e.what();
  }
}

}  // namespace test_unit_io_family_manifest
