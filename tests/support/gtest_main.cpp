// The main() of every test executable: GoogleTest's, plus an exit status that
// tells ctest when a test was skipped (GTEST_SKIP: data or a tool missing), so
// that ctest reports the test as skipped instead of passed (SKIP_RETURN_CODE in
// tests/CMakeLists.txt).
//
// A ctest test is one test file (a --gtest_filter on its suites). It is reported
//  - failed  (exit 1) when any of its tests failed, whatever else happened;
//  - skipped (exit kSkippedExitCode) when none failed and at least one was
//    skipped: the file did not run whole, and that must be visible;
//  - passed  (exit 0) when every selected test ran and passed.
#include <gtest/gtest.h>

namespace {

// The Automake convention for "skipped", also what tests/CMakeLists.txt declares.
constexpr int kSkippedExitCode = 77;

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  // RUN_ALL_TESTS is nonzero on any failure, ad hoc ones (outside a test) included.
  if (RUN_ALL_TESTS() != 0) return 1;
  return testing::UnitTest::GetInstance()->skipped_test_count() > 0 ? kSkippedExitCode : 0;
}
