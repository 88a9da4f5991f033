// End-to-end: the dispatcher (sysid --help, --version, no verb).
#include <sysid/config.hpp>

#include <gtest/gtest.h>

#include "run_cli.hpp"

namespace test_app_main {

using namespace sysid::test;

TEST(MainApp, HelpListsEveryVerbWithADescription) {
  const CliResult r = run_cli({"--help"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  for (const char* verb : {"n4sid", "simulate", "compare", "show", "excite"}) {
    const auto pos = r.out.find(std::string("\n  ") + verb + " ");
    ASSERT_NE(pos, std::string::npos) << verb << "\n" << r.out;
    const std::string line = r.out.substr(pos + 1, r.out.find('\n', pos + 1) - pos - 1);
    EXPECT_GT(line.size(), std::string(verb).size() + 20) << "no description: " << line;
  }
  EXPECT_NE(r.out.find("Exit codes"), std::string::npos);
}

TEST(MainApp, VersionPrintsTheVersion) {
  const CliResult r = run_cli({"--version"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(r.out, std::string(SYSID_VERSION_STRING) + "\n");
}

TEST(MainApp, NoVerbOrUnknownVerbIsAUsageError) {
  CliResult r = run_cli({});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_FALSE(r.err.empty());
  r = run_cli({"identify-everything"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
}

}  // namespace test_app_main
