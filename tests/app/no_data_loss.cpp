// End-to-end tests of the promise "no data loss" (DESIGN.md, issue 8): an output
// never replaces an input or an existing file unless --force is given, two outputs
// of one run never name one file, and a run killed at any moment leaves either no
// output or a complete one, and no temporary behind.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "run_cli.hpp"

namespace test_app_no_data_loss {

namespace {

using sysid::test::CliResult;
using sysid::test::contains;
using sysid::test::describe;
using sysid::test::read_text_file;
using sysid::test::run_cli;
using sysid::test::TempDir;
using sysid::test::write_text_file;

/// Every file in `dir` whose name marks it as a temporary of an atomic write.
std::vector<std::string> leftover_temporaries(const std::filesystem::path& dir) {
  std::vector<std::string> found;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (contains(entry.path().filename().string(), ".tmp.")) found.push_back(entry.path().string());
  return found;
}

/// The arguments of a short excitation run writing `out`.
std::vector<std::string> excite_args(const std::string& out, long samples) {
  return {"excite", "--signal", "multisine", "--fs", "1000", "--band", "1:200", "--samples", std::to_string(samples),
          "--out", out};
}

TEST(NoDataLoss, ExistingOutputIsKeptWithoutForceAndReplacedWithIt) {
  TempDir tmp;
  const std::string out = tmp / "u.csv";
  write_text_file(out, "precious\n");

  CliResult r = run_cli(excite_args(out, 100));
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "already exists")) << r.err;
  EXPECT_TRUE(contains(r.err, "--force")) << r.err;
  EXPECT_EQ(read_text_file(out), "precious\n");

  std::vector<std::string> forced = excite_args(out, 100);
  forced.push_back("--force");
  r = run_cli(forced);
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(read_text_file(out), "t,")) << "the forced run did not replace the file";
  EXPECT_TRUE(leftover_temporaries(tmp.path()).empty());
}

TEST(NoDataLoss, ARefusedOutputCostsNothingEvenWhenAnotherOutputIsNew) {
  // n4sid with --out (new) and --plot (existing): the whole run is refused before
  // any work, so the new file is not written either.
  TempDir tmp;
  const std::string log = tmp / "u.csv";
  ASSERT_EQ(run_cli(excite_args(log, 2000)).exit_code, 0);
  const std::string plot = tmp / "plot.svg";
  write_text_file(plot, "<svg/>\n");

  const CliResult r = run_cli({"n4sid", log, "--inputs", "u", "--outputs", "u", "--order", "2", "--out",
                               tmp / "model.json", "--plot", plot});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, plot)) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp / "model.json"));
  EXPECT_EQ(read_text_file(plot), "<svg/>\n");
}

TEST(NoDataLoss, ForceNeverAllowsReplacingAnInput) {
  TempDir tmp;
  const std::string log = tmp / "u.csv";
  ASSERT_EQ(run_cli(excite_args(log, 200)).exit_code, 0);
  const std::string before = read_text_file(log);
  const CliResult r = run_cli({"filter", log, "--columns", "u", "--lowpass", "50", "--out", log, "--force"});
  EXPECT_NE(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.err, "refusing to overwrite input")) << r.err;
  EXPECT_EQ(read_text_file(log), before);
}

TEST(NoDataLoss, EveryVerbThatWritesFilesOffersForce) {
  const CliResult help = run_cli({"--help"});
  ASSERT_EQ(help.exit_code, 0);
  int writing_verbs = 0;
  for (const char* verb : {"n4sid", "simulate", "compare", "show", "excite", "resid", "frf", "psd", "filter", "arx",
                           "ar", "armax", "arma", "oe", "assemble", "hsv", "reduce", "lms", "okid", "era", "diagnose",
                           "check"}) {
    ASSERT_TRUE(contains(help.out, verb)) << verb << " is not in the verb list";
    const CliResult r = run_cli({verb, "--help"});
    ASSERT_EQ(r.exit_code, 0) << verb << "\n" << describe(r);
    const bool writes = contains(r.out, "--out ") || contains(r.out, "--plot") || contains(r.out, "--json") ||
                        contains(r.out, "--curve");
    if (!writes) continue;
    ++writing_verbs;
    EXPECT_TRUE(contains(r.out, "--force")) << "sysid " << verb << " writes files but has no --force";
  }
  EXPECT_GE(writing_verbs, 18);
}

/// Starts the sysid binary with `args` (stdout and stderr to /dev/null); returns its pid.
pid_t spawn_cli(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  std::string binary = SYSID_BINARY;
  argv.push_back(binary.data());
  std::vector<std::string> copy = args;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (std::FILE* devnull = std::freopen("/dev/null", "w", stdout); devnull == nullptr) ::_exit(126);
    if (std::FILE* devnull = std::freopen("/dev/null", "w", stderr); devnull == nullptr) ::_exit(126);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

TEST(NoDataLoss, ARunKilledAtAnyMomentLeavesNoPartialFile) {
  // A multi-million-sample excitation: generating, formatting and writing the CSV
  // take about a second, so kills spread over the run land in every phase,
  // including the write itself. After each kill the output is absent or complete
  // (the full row count), and no temporary is left behind.
  TempDir tmp;
  const long samples = 2'000'000;
  const std::string reference = tmp / "reference.csv";
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(run_cli(excite_args(reference, samples)).exit_code, 0);
  const double run_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string complete = read_text_file(reference);
  std::filesystem::remove(reference);

  int absent = 0, whole = 0;
  for (double fraction : {0.05, 0.2, 0.4, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95, 0.98, 1.0, 1.02}) {
    const std::string out = tmp / "killed.csv";
    const pid_t pid = spawn_cli(excite_args(out, samples));
    ASSERT_GT(pid, 0);
    std::this_thread::sleep_for(std::chrono::duration<double>(fraction * run_seconds));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    if (std::filesystem::exists(out)) {
      EXPECT_EQ(read_text_file(out), complete) << "a partial output after a kill at " << fraction << " of the run";
      ++whole;
      std::filesystem::remove(out);
    } else {
      ++absent;
    }
    EXPECT_TRUE(leftover_temporaries(tmp.path()).empty()) << "a temporary left after a kill at " << fraction;
  }
  // The spread must have produced both outcomes, or the test proved nothing.
  EXPECT_GT(absent, 0);
  RecordProperty("killed_before_commit", absent);
  RecordProperty("completed_before_kill", whole);
}

}  // namespace

}  // namespace test_app_no_data_loss
