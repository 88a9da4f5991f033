#include "sysid/io/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "sysid/core/errors.hpp"

namespace test_unit_io_atomic_file {

namespace fs = std::filesystem;

namespace {

class AtomicFile : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937_64 rng(std::random_device{}());
    m_dir = fs::temp_directory_path() / ("sysid_io_atomic_" + std::to_string(::getpid()) + "_" + std::to_string(rng()));
    fs::create_directories(m_dir);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(m_dir, ec);
  }
  static std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  /// Every entry of the directory (temporaries start with '.', so list them all).
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(m_dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  fs::path m_dir;
};

TEST_F(AtomicFile, WritesContentAndLeavesNoTemporary) {
  const fs::path p = m_dir / "out.csv";
  // Binary content with NUL bytes and no final newline: written byte for byte.
  const std::string content = std::string("a,b\n1,2\n") + '\0' + "\xff tail";
  sysid::write_file_atomically(p.string(), content);
  EXPECT_EQ(slurp(p), content);
  EXPECT_EQ(entries(), std::vector<std::string>{"out.csv"});
}

TEST_F(AtomicFile, ReplacesExistingFileAndKeepsItsMode) {
  const fs::path p = m_dir / "model.json";
  { std::ofstream(p) << "old contents that are longer than the new ones\n"; }
  ASSERT_EQ(::chmod(p.c_str(), 0640), 0);
  sysid::write_file_atomically(p.string(), "new\n");
  EXPECT_EQ(slurp(p), "new\n");
  struct stat st {};
  ASSERT_EQ(::stat(p.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  EXPECT_EQ(entries(), std::vector<std::string>{"model.json"});
}

TEST_F(AtomicFile, EmptyContentsGiveAnEmptyFile) {
  const fs::path p = m_dir / "empty.txt";
  sysid::write_file_atomically(p.string(), "");
  EXPECT_TRUE(fs::exists(p));
  EXPECT_EQ(fs::file_size(p), 0u);
}

TEST_F(AtomicFile, MissingDirectoryThrowsDataErrorAndLeavesNothing) {
  const fs::path p = m_dir / "no_such_dir" / "out.csv";
  try {
    sysid::write_file_atomically(p.string(), "x");
    FAIL() << "expected DataError";
  } catch (const sysid::DataError& e) {
    EXPECT_EQ(e.file(), p.string());
    EXPECT_NE(e.message().find("does not exist"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(m_dir / "no_such_dir"));
  EXPECT_TRUE(entries().empty());
}

TEST_F(AtomicFile, ParentIsAFileThrows) {
  { std::ofstream(m_dir / "plain") << "x"; }
  try {
    sysid::write_file_atomically((m_dir / "plain" / "out.csv").string(), "y");
    FAIL() << "expected DataError";
  } catch (const sysid::DataError& e) {
    EXPECT_NE(e.message().find("not a directory"), std::string::npos) << e.what();
  }
  EXPECT_EQ(entries(), std::vector<std::string>{"plain"});
}

TEST_F(AtomicFile, TargetIsADirectoryThrows) {
  fs::create_directory(m_dir / "sub");
  EXPECT_THROW(sysid::write_file_atomically((m_dir / "sub").string(), "x"), sysid::DataError);
  EXPECT_THROW(sysid::write_file_atomically((m_dir / "sub").string() + "/", "x"), sysid::DataError);
  EXPECT_EQ(entries(), std::vector<std::string>{"sub"});
  EXPECT_TRUE(fs::is_empty(m_dir / "sub"));
}

TEST_F(AtomicFile, UnwritableDirectoryThrowsPermissionDenied) {
  const fs::path ro = m_dir / "ro";
  fs::create_directory(ro);
  ASSERT_EQ(::chmod(ro.c_str(), 0555), 0);
  const std::string target = (ro / "out.csv").string();
  // Root ignores directory permissions (and CI runs as root): try as "nobody" in
  // a child process instead. Exit code 0: DataError naming the cause.
  auto attempt = [&]() -> int {
    try {
      sysid::write_file_atomically(target, "x");
      return 1;
    } catch (const sysid::DataError& e) {
      return e.file() == target && e.message().find("ermission denied") != std::string::npos ? 0 : 2;
    } catch (...) {
      return 3;
    }
  };
  if (::geteuid() == 0) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      if (::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(4);
      ::_exit(attempt());
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "1: no error, 2: wrong message, 3: wrong exception, 4: setuid failed";
  } else {
    EXPECT_EQ(attempt(), 0);
  }
  ::chmod(ro.c_str(), 0755);
  EXPECT_TRUE(fs::is_empty(ro));
}

TEST_F(AtomicFile, SymlinkTargetIsFollowed) {
  const fs::path real = m_dir / "real.txt";
  const fs::path link = m_dir / "link.txt";
  { std::ofstream(real) << "old"; }
  fs::create_symlink(real, link);
  sysid::write_file_atomically(link.string(), "new");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(slurp(real), "new");
}

TEST_F(AtomicFile, RelativePathInCurrentDirectory) {
  const fs::path old_cwd = fs::current_path();
  fs::current_path(m_dir);
  sysid::write_file_atomically("plain.txt", "abc");
  fs::current_path(old_cwd);
  EXPECT_EQ(slurp(m_dir / "plain.txt"), "abc");
  EXPECT_EQ(entries(), std::vector<std::string>{"plain.txt"});
}

TEST_F(AtomicFile, ReadWholeFile) {
  const fs::path p = m_dir / "in.txt";
  std::string big(300000, 'x');
  for (std::size_t i = 0; i < big.size(); i += 97) big[i] = '\n';
  sysid::write_file_atomically(p.string(), big);
  EXPECT_EQ(sysid::read_whole_file(p.string()), big);
  EXPECT_THROW(sysid::read_whole_file((m_dir / "missing.txt").string()), sysid::DataError);
  EXPECT_THROW(sysid::read_whole_file(m_dir.string()), sysid::DataError);
  try {
    sysid::read_whole_file((m_dir / "missing.txt").string());
  } catch (const sysid::DataError& e) {
    EXPECT_NE(e.message().find("No such file"), std::string::npos) << e.what();
  }
}

TEST_F(AtomicFile, RefuseToOverwriteInput) {
  const fs::path in = m_dir / "log.csv";
  { std::ofstream(in) << "t,y\n0,1\n"; }
  const std::string in_s = in.string();
  // The same file reached through different spellings.
  EXPECT_THROW(sysid::refuse_to_overwrite_input(in_s, {"other.csv", in_s}), std::invalid_argument);
  EXPECT_THROW(sysid::refuse_to_overwrite_input((m_dir / "." / "log.csv").string(), {in_s}), std::invalid_argument);
  EXPECT_THROW(sysid::refuse_to_overwrite_input((m_dir / "sub" / ".." / "log.csv").string(), {in_s}),
               std::invalid_argument);
  fs::create_symlink(in, m_dir / "alias.csv");
  EXPECT_THROW(sysid::refuse_to_overwrite_input((m_dir / "alias.csv").string(), {in_s}), std::invalid_argument);
  fs::create_hard_link(in, m_dir / "hard.csv");
  EXPECT_THROW(sysid::refuse_to_overwrite_input((m_dir / "hard.csv").string(), {in_s}), std::invalid_argument);
  // Different files (existing or not) are fine.
  EXPECT_NO_THROW(sysid::refuse_to_overwrite_input((m_dir / "out.csv").string(), {in_s}));
  EXPECT_NO_THROW(sysid::refuse_to_overwrite_input((m_dir / "out.csv").string(), {}));
}

}  // namespace

}  // namespace test_unit_io_atomic_file
