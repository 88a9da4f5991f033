#include "sysid/io/matrix_market.hpp"

#include <gtest/gtest.h>

#include "run_cli.hpp"
#include "sparse_bits.hpp"
#include <unistd.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "sysid/core/errors.hpp"

namespace test_unit_io_matrix_market {

namespace fs = std::filesystem;
using sysid::DataError;
using Sparse = Eigen::SparseMatrix<double>;

namespace {

using sysid::test::bits;
using sysid::test::identical;
using sysid::test::TempDir;  // tests/support/run_cli.hpp

/// Values that break a careless writer: non-terminating binary fractions, the
/// extremes of the exponent range, subnormals, both zeros.
double awkward(std::mt19937_64& rng) {
  static const double pool[] = {1.0 / 3.0,
                                -2.0 / 3.0,
                                1e-300,
                                -0.0,
                                0.0,
                                4.9406564584124654e-324,
                                std::numeric_limits<double>::min(),
                                std::numeric_limits<double>::max(),
                                -std::numeric_limits<double>::max(),
                                0.1,
                                1e22,
                                123456789.0 / 7.0};
  std::uniform_int_distribution<int> pick(0, 2 * static_cast<int>(std::size(pool)) - 1);
  const int k = pick(rng);
  if (k < static_cast<int>(std::size(pool))) return pool[k];
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> expo(-200, 200);
  return std::ldexp(normal(rng), expo(rng));
}

/// Random rows x cols matrix with about `density` of its entries stored; explicit
/// zeros among them (the pool holds +0 and -0).
Sparse random_general(std::mt19937_64& rng, int rows, int cols, double density) {
  std::bernoulli_distribution keep(density);
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < rows; ++i)
      if (keep(rng)) t.emplace_back(i, j, awkward(rng));
  Sparse a(rows, cols);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

Sparse random_symmetric(std::mt19937_64& rng, int n, double density) {
  std::bernoulli_distribution keep(density);
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < n; ++j)
    for (int i = j; i < n; ++i)
      if (keep(rng)) {
        const double v = awkward(rng);
        t.emplace_back(i, j, v);
        if (i != j) t.emplace_back(j, i, v);
      }
  Sparse a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

Sparse parse(const std::string& text) { return sysid::parse_matrix_market(text, "test.mtx"); }

/// Parsing `text` must fail at line:column with `word` in the message.
void expect_error(const std::string& text, long line, long column, const std::string& word) {
  SCOPED_TRACE("text:\n" + text);
  try {
    parse(text);
    ADD_FAILURE() << "no DataError";
  } catch (const DataError& e) {
    EXPECT_EQ(e.file(), "test.mtx");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.column(), column) << e.what();
    EXPECT_NE(e.message().find(word), std::string::npos) << "'" << word << "' not in: " << e.what();
  }
}

const std::string k_general = "%%MatrixMarket matrix coordinate real general\n";
const std::string k_symmetric = "%%MatrixMarket matrix coordinate real symmetric\n";

}  // namespace

// ---- round trips ---------------------------------------------------------------

TEST(MatrixMarket, GeneralRoundTripIsBitExact) {
  std::mt19937_64 rng(20240611);
  for (const auto& [rows, cols] : {std::pair{37, 23}, std::pair{1, 1}, std::pair{5, 40}, std::pair{60, 60}}) {
    const Sparse a = random_general(rng, rows, cols, 0.2);
    const std::string text = sysid::format_matrix_market(a, false);
    EXPECT_EQ(text.rfind("%%MatrixMarket matrix coordinate real general\n", 0), 0u);
    EXPECT_TRUE(identical(parse(text), a)) << rows << "x" << cols;
  }
}

TEST(MatrixMarket, SymmetricRoundTripIsBitExactAndStoresTheLowerTriangle) {
  std::mt19937_64 rng(7);
  for (int n : {1, 9, 50}) {
    const Sparse a = random_symmetric(rng, n, 0.25);
    ASSERT_TRUE(sysid::is_exactly_symmetric(a));
    const std::string text = sysid::format_matrix_market(a, true);
    EXPECT_EQ(text.rfind("%%MatrixMarket matrix coordinate real symmetric\n", 0), 0u);
    // Stored count = diagonal + strictly lower entries.
    Eigen::Index lower = 0;
    for (Eigen::Index k = 0; k < a.outerSize(); ++k)
      for (Sparse::InnerIterator it(a, k); it; ++it) lower += it.row() >= it.col() ? 1 : 0;
    EXPECT_NE(text.find("\n" + std::to_string(n) + " " + std::to_string(n) + " " + std::to_string(lower) + "\n"),
              std::string::npos);
    EXPECT_TRUE(identical(parse(text), a)) << "n = " << n;
  }
}

TEST(MatrixMarket, FileRoundTripAndEmptyMatrix) {
  TempDir dir;
  std::mt19937_64 rng(3);
  const Sparse a = random_symmetric(rng, 30, 0.1);
  const std::string sym = (dir.path() / "a.sym.mtx").string();
  const std::string gen = (dir.path() / "a.gen.mtx").string();
  sysid::write_matrix_market(sym, a, true);
  sysid::write_matrix_market(gen, a, false);
  EXPECT_TRUE(identical(sysid::read_matrix_market(sym), a));
  EXPECT_TRUE(identical(sysid::read_matrix_market(gen), a));

  const Sparse empty(4, 0);
  EXPECT_TRUE(identical(parse(sysid::format_matrix_market(empty, false)), empty));
  EXPECT_TRUE(identical(parse(sysid::format_matrix_market(Sparse(3, 3), true)), Sparse(3, 3)));
}

TEST(MatrixMarket, WriterRefusesWhatTheReaderWouldNotReturn) {
  Sparse a(3, 3);
  a.insert(1, 0) = 1.0 / 3.0;
  a.insert(0, 1) = std::nextafter(1.0 / 3.0, 1.0);  // one ulp off: not exactly symmetric
  EXPECT_FALSE(sysid::is_exactly_symmetric(a));
  EXPECT_THROW(sysid::format_matrix_market(a, true), std::invalid_argument);
  EXPECT_NO_THROW(sysid::format_matrix_market(a, false));

  Sparse missing_mirror(2, 2);
  missing_mirror.insert(1, 0) = 2.0;
  EXPECT_THROW(sysid::format_matrix_market(missing_mirror, true), std::invalid_argument);
  EXPECT_THROW(sysid::format_matrix_market(Sparse(2, 3), true), std::invalid_argument);

  Sparse with_nan(2, 2);
  with_nan.insert(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sysid::format_matrix_market(with_nan, false), std::invalid_argument);
  EXPECT_FALSE(sysid::is_exactly_symmetric(with_nan));
}

// ---- accepted variants ---------------------------------------------------------

TEST(MatrixMarket, SymmetricStorageIsExpanded) {
  const Sparse a = parse(k_symmetric +
                         "% a comment\n"
                         "3 3 4\n"
                         "1 1 4.0\n"
                         "2 1 -1.5\n"
                         "3 2 2e-3\n"
                         "3 3 7\n");
  Eigen::MatrixXd expected(3, 3);
  expected << 4.0, -1.5, 0.0, -1.5, 0.0, 2e-3, 0.0, 2e-3, 7.0;
  EXPECT_EQ(Eigen::MatrixXd(a), expected);
  EXPECT_EQ(a.nonZeros(), 6);
  EXPECT_TRUE(a.isCompressed());
}

TEST(MatrixMarket, DuplicateEntriesAreSummed) {
  const Sparse g = parse(k_general + "2 2 4\n1 1 1.5\n2 1 1\n1 1 2.25\n2 1 -3\n");
  EXPECT_EQ(g.coeff(0, 0), 3.75);
  EXPECT_EQ(g.coeff(1, 0), -2.0);
  EXPECT_EQ(g.nonZeros(), 2);
  // In symmetric storage the sum is mirrored as well.
  const Sparse s = parse(k_symmetric + "3 3 3\n3 1 0.5\n3 1 0.25\n3 1 0.125\n");
  EXPECT_EQ(s.coeff(2, 0), 0.875);
  EXPECT_EQ(s.coeff(0, 2), 0.875);
  EXPECT_EQ(s.nonZeros(), 2);
}

TEST(MatrixMarket, ArrayFormat) {
  // Column-major: column 1 = (1, 2), column 2 = (0, 4), column 3 = (5, -6).
  const Sparse g = parse("%%MatrixMarket matrix array real general\n2 3\n1\n2\n0\n4\n5\n-6\n");
  Eigen::MatrixXd expected(2, 3);
  expected << 1, 0, 5, 2, 4, -6;
  EXPECT_EQ(Eigen::MatrixXd(g), expected);
  EXPECT_EQ(g.nonZeros(), 5);  // the dense zero is not stored

  // Symmetric: lower triangle by columns: (1,1) (2,1) (3,1) (2,2) (3,2) (3,3).
  const Sparse s = parse("%%MatrixMarket matrix array real symmetric\n3 3\n11\n21\n31\n22\n32\n33\n");
  Eigen::MatrixXd full(3, 3);
  full << 11, 21, 31, 21, 22, 32, 31, 32, 33;
  EXPECT_EQ(Eigen::MatrixXd(s), full);
}

TEST(MatrixMarket, IntegerFieldCommentsBlankLinesCrLfCaseAndBom) {
  const Sparse a = parse(
      "\xEF\xBB\xBF%%MatrixMarket MATRIX Coordinate INTEGER General\r\n"
      "% exported by some FE package\r\n"
      "\r\n"
      "   2 2 2   \r\n"
      "%  interleaved comment\r\n"
      "1\t1\t-7\r\n"
      "\r\n"
      "2 2 +3\r\n");
  EXPECT_EQ(a.coeff(0, 0), -7.0);
  EXPECT_EQ(a.coeff(1, 1), 3.0);
  EXPECT_EQ(parse(k_general + "1 1 1\n1 1 +2.5e+1").coeff(0, 0), 25.0);  // no final newline
}

// ---- errors: banner ------------------------------------------------------------

TEST(MatrixMarketErrors, Banner) {
  expect_error("", 1, 1, "empty");
  expect_error("3 3 1\n1 1 1\n", 1, 1, "banner");
  expect_error("%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 1\n", 1, 1, "banner");
  expect_error("%%MatrixMarket vector coordinate real general\n", 1, 16, "matrix");
  expect_error("%%MatrixMarket matrix sparse real general\n", 1, 23, "coordinate");
  expect_error("%%MatrixMarket matrix coordinate\n", 1, 34, "field");
  expect_error("%%MatrixMarket matrix coordinate real\n", 1, 39, "symmetry");
  expect_error("%%MatrixMarket matrix coordinate real general extra\n", 1, 47, "extra");
  expect_error("%%MatrixMarket matrix coordinate double general\n", 1, 34, "real, integer");
}

TEST(MatrixMarketErrors, UnsupportedKindsNameTheSupportedOnes) {
  expect_error("%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1 0\n", 1, 34, "real, integer");
  expect_error("%%MatrixMarket matrix coordinate pattern general\n1 1 1\n1 1\n", 1, 34, "not supported");
  expect_error("%%MatrixMarket matrix coordinate real hermitian\n", 1, 39, "general, symmetric");
  expect_error("%%MatrixMarket matrix coordinate real skew-symmetric\n", 1, 39, "not supported");
  expect_error("%%MatrixMarket matrix array complex general\n", 1, 29, "not supported");
}

// ---- errors: size line ---------------------------------------------------------

TEST(MatrixMarketErrors, SizeLine) {
  expect_error(k_general, 2, 1, "size line");
  expect_error(k_general + "% only comments\n\n", 4, 1, "size line");
  expect_error(k_general + "3 x 1\n", 2, 3, "columns");
  expect_error(k_general + "3 3\n", 2, 5, "rows columns entries");
  expect_error(k_general + "3 3 1 7\n", 2, 7, "extra");
  expect_error("%%MatrixMarket matrix array real general\n2 2 4\n", 2, 5, "extra");
  expect_error(k_general + "-3 3 1\n", 2, 1, "non-negative");
  expect_error(k_general + "3 3 -1\n", 2, 5, "non-negative");
  expect_error(k_general + "3.0 3 1\n", 2, 1, "rows");
  expect_error(k_general + "99999999999999999999 3 1\n", 2, 1, "absurdly large");
  expect_error(k_general + "3 3000000000 1\n", 2, 3, "limit");
  expect_error(k_general + "2 3 7\n", 2, 5, "more than rows x columns = 6");
  expect_error(k_general + "65536 65536 4294967296\n", 2, 13, "limit");
  expect_error(k_symmetric + "3 4 1\n", 2, 3, "square");
}

// ---- errors: entries -----------------------------------------------------------

TEST(MatrixMarketErrors, IndicesOutOfRange) {
  expect_error(k_general + "3 2 1\n4 1 1.0\n", 3, 1, "outside 1..3");
  expect_error(k_general + "3 2 1\n0 1 1.0\n", 3, 1, "outside 1..3");
  expect_error(k_general + "3 2 1\n% c\n1 3 1.0\n", 4, 3, "outside 1..2");
  expect_error(k_general + "3 2 1\n  1 -1 1.0\n", 3, 5, "outside 1..2");
  expect_error(k_general + "3 2 1\n1.5 1 1.0\n", 3, 1, "row index");
  expect_error(k_general + "3 2 1\n1 x 1.0\n", 3, 3, "column index");
}

TEST(MatrixMarketErrors, UpperTriangleInSymmetricFile) {
  expect_error(k_symmetric + "3 3 2\n1 1 1\n1 3 5.0\n", 4, 1, "upper triangle");
  expect_error("%%MatrixMarket matrix coordinate real symmetric\n3 3 1\n2 3 5.0\n", 3, 1, "row >= column");
}

TEST(MatrixMarketErrors, ValuesThatAreNotFiniteNumbers) {
  expect_error(k_general + "2 2 1\n1 1 abc\n", 3, 5, "expected a number");
  expect_error(k_general + "2 2 1\n1 1 1.5x\n", 3, 5, "expected a number");
  expect_error(k_general + "2 2 1\n1 1 +-1\n", 3, 5, "expected a number");
  expect_error(k_general + "2 2 1\n1 1 nan\n", 3, 5, "NaN");
  expect_error(k_general + "2 2 1\n1 1 -inf\n", 3, 5, "NaN or Inf");
  expect_error(k_general + "2 2 1\n2 2 1e999\n", 3, 5, "range of a double");
  expect_error("%%MatrixMarket matrix coordinate integer general\n2 2 1\n1 1 1.5\n", 3, 5, "integer");
  expect_error("%%MatrixMarket matrix array real general\n1 2\n0.5\nNaN\n", 4, 1, "NaN");
}

TEST(MatrixMarketErrors, MissingAndExtraFields) {
  expect_error(k_general + "2 2 1\n1 1\n", 3, 5, "3 fields");
  expect_error(k_general + "2 2 1\n1 1 1 0\n", 3, 7, "4th field");
  expect_error("%%MatrixMarket matrix array real general\n2 1\n1 2\n3\n", 3, 3, "one value per line");
}

TEST(MatrixMarketErrors, FewerOrMoreEntriesThanAnnounced) {
  // Fewer: reported at the end of the file, saying how many were found.
  expect_error(k_general + "3 3 2\n1 1 1\n", 4, 1, "1 of the 2 entries announced on line 2");
  expect_error(k_general + "3 3 2\n1 1 1", 3, 6, "ends after 1 of the 2");
  expect_error(k_general + "% c\n3 3 2\n\n% c\n", 6, 1, "0 of the 2 entries announced on line 3");
  expect_error("%%MatrixMarket matrix array real symmetric\n3 3\n1\n2\n3\n4\n5\n", 8, 1, "5 of the 6");
  // More: reported at the first extra entry.
  expect_error(k_general + "3 3 1\n1 1 1\n% c\n  2 2 2\n3 3 3\n", 5, 3, "more entries than the 1 announced");
  expect_error("%%MatrixMarket matrix array real general\n1 1\n1\n2\n", 4, 1, "more entries");
}

TEST(MatrixMarketErrors, UnreadableFile) {
  TempDir dir;
  const std::string missing = (dir.path() / "nope.mtx").string();
  try {
    sysid::read_matrix_market(missing);
    ADD_FAILURE() << "no DataError";
  } catch (const DataError& e) {
    EXPECT_EQ(e.file(), missing);
  }
}

}  // namespace test_unit_io_matrix_market
