#include "sysid/io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <system_error>

#include "sysid/core/errors.hpp"

namespace sysid {
namespace {

namespace fs = std::filesystem;

std::string errno_text(int err) { return std::generic_category().message(err); }

/// Closes the descriptor and removes the temporary (once it has a name) unless
/// released: every early exit (exception) leaves nothing behind.
class TempFileGuard {
 public:
  explicit TempFileGuard(int fd) : m_fd(fd) {}
  TempFileGuard(const TempFileGuard&) = delete;
  TempFileGuard& operator=(const TempFileGuard&) = delete;
  ~TempFileGuard() {
    if (m_fd >= 0) ::close(m_fd);
    if (!m_released && !m_path.empty()) ::unlink(m_path.c_str());
  }
  void set_name(std::string path) { m_path = std::move(path); }
  /// Closes explicitly so that a failing close (delayed write error on NFS) is seen.
  int close_checked() {
    const int rc = ::close(m_fd);
    m_fd = -1;
    return rc;
  }
  void release() { m_released = true; }
  int fd() const { return m_fd; }

 private:
  std::string m_path;
  int m_fd;
  bool m_released = false;
};

/// Random suffix: pid alone is not unique across threads of one process, so a
/// per-process random stream plus a counter is appended.
std::string unique_suffix() {
  static std::atomic<unsigned long long> counter{0};
  thread_local std::mt19937_64 rng{std::random_device{}() ^ (static_cast<unsigned long long>(::getpid()) << 32)};
  char buf[64];
  std::snprintf(buf, sizeof buf, "%ld.%016llx%llx", static_cast<long>(::getpid()),
                static_cast<unsigned long long>(rng()), counter.fetch_add(1));
  return buf;
}

std::string temporary_name(const fs::path& dir, const fs::path& target) {
  return (dir / ("." + target.filename().string() + ".tmp." + unique_suffix())).string();
}

/// Writes all of `contents`, gives the file the mode of the file it replaces (if
/// any) and fsyncs it.
void write_contents(int fd, const std::string& contents, const std::string& path, const struct stat* replaced) {
  const char* p = contents.data();
  std::size_t left = contents.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      throw DataError(path, 0, 0, "cannot write: " + errno_text(err));
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  // Keep the permissions a user gave the file being replaced.
  if (replaced != nullptr) (void)::fchmod(fd, replaced->st_mode & 07777);
  if (::fsync(fd) != 0) {
    const int err = errno;
    throw DataError(path, 0, 0, "cannot write: fsync failed: " + errno_text(err));
  }
}

/// Gives the complete unnamed (O_TMPFILE) file a fresh temporary name in `dir`;
/// empty when the system refuses (no /proc, or a file system without linkat of
/// unnamed files). AT_EMPTY_PATH needs CAP_DAC_READ_SEARCH, the /proc/self/fd path
/// does not (open(2), "O_TMPFILE").
std::string name_unnamed_file(int fd, const fs::path& dir, const fs::path& target) {
  const std::string proc_path = "/proc/self/fd/" + std::to_string(fd);
  for (int attempt = 0; attempt < 8; ++attempt) {
    std::string tmp = temporary_name(dir, target);
    if (::linkat(AT_FDCWD, proc_path.c_str(), AT_FDCWD, tmp.c_str(), AT_SYMLINK_FOLLOW) == 0) return tmp;
    if (errno != EEXIST) break;
  }
  return {};
}

/// Closes the complete temporary, renames it over the target and makes the rename
/// durable.
void commit(TempFileGuard& guard, const std::string& tmp, const fs::path& target, const fs::path& dir,
            const std::string& path) {
  if (guard.close_checked() != 0) {
    const int err = errno;
    throw DataError(path, 0, 0, "cannot write: close failed: " + errno_text(err));
  }
  if (::rename(tmp.c_str(), target.c_str()) != 0) {
    const int err = errno;
    throw DataError(path, 0, 0, "cannot replace the file: " + errno_text(err));
  }
  guard.release();

  // Some file systems refuse fsync on a directory (EINVAL), which does not make the
  // write less complete.
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    (void)::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace

void write_file_atomically(const std::string& path, const std::string& contents) {
  if (path.empty()) throw std::invalid_argument("write_file_atomically: empty path");

  fs::path target(path);
  std::error_code ec;
  // Replace the file a symbolic link points to, not the link itself.
  if (fs::is_symlink(fs::symlink_status(target, ec))) {
    const fs::path resolved = fs::weakly_canonical(target, ec);
    if (!ec) target = resolved;
  }
  if (!target.has_filename()) throw DataError(path, 0, 0, "cannot write: the path names a directory");
  fs::path dir = target.parent_path();
  if (dir.empty()) dir = ".";

  const fs::file_status dir_status = fs::status(dir, ec);
  if (!fs::exists(dir_status))
    throw DataError(path, 0, 0, "cannot write: directory '" + dir.string() + "' does not exist");
  if (!fs::is_directory(dir_status))
    throw DataError(path, 0, 0, "cannot write: '" + dir.string() + "' is not a directory");

  struct stat old_stat {};
  const bool target_exists = ::stat(target.c_str(), &old_stat) == 0;
  if (target_exists && S_ISDIR(old_stat.st_mode)) throw DataError(path, 0, 0, "cannot write: the path is a directory");
  const struct stat* replaced = target_exists ? &old_stat : nullptr;

#ifdef O_TMPFILE
  // Linux: the file has no name while it is written, so a run killed at any point
  // (even by SIGKILL) leaves no partial file; it is named only when complete, an
  // instant before the rename.
  if (const int unnamed = ::open(dir.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666); unnamed >= 0) {
    TempFileGuard guard(unnamed);
    write_contents(unnamed, contents, path, replaced);
    if (std::string tmp = name_unnamed_file(unnamed, dir, target); !tmp.empty()) {
      guard.set_name(tmp);
      commit(guard, tmp, target, dir, path);
      return;
    }
  }  // else (kernel or file system without O_TMPFILE, no /proc): a named temporary
#endif

  // O_EXCL makes a name clash an error instead of a shared file; retry a few
  // times with a fresh random suffix.
  std::string tmp;
  int fd = -1;
  for (int attempt = 0; attempt < 8 && fd < 0; ++attempt) {
    tmp = temporary_name(dir, target);
    fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) {
    const int err = errno;
    throw DataError(path, 0, 0, "cannot write: cannot create a temporary file in '" + dir.string() + "': " + errno_text(err));
  }
  TempFileGuard guard(fd);
  guard.set_name(tmp);
  write_contents(fd, contents, path, replaced);
  commit(guard, tmp, target, dir, path);
}

int open_for_reading(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    throw DataError(path, 0, 0, "cannot open the file: " + errno_text(err));
  }
  return fd;
}

std::string read_whole_file(const std::string& path) {
  const int fd = open_for_reading(path);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  return read_whole_descriptor(fd, path);
}

std::string read_whole_descriptor(int fd, const std::string& path) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    throw DataError(path, 0, 0, "cannot read the file: " + errno_text(err));
  }
  if (S_ISDIR(st.st_mode)) throw DataError(path, 0, 0, "cannot read the file: it is a directory");

  std::string out;
  // Regular files: one read of the known size (then a probe for growth since the
  // stat). Pipes and the like report size 0; the buffer then grows as data arrives.
  out.resize(S_ISREG(st.st_mode) ? static_cast<std::size_t>(st.st_size) : 0);
  std::size_t have = 0;
  for (;;) {
    if (have == out.size()) {
      char probe[4096];
      ssize_t n;
      do n = ::read(fd, probe, sizeof probe);
      while (n < 0 && errno == EINTR);
      if (n < 0) {
        const int err = errno;
        throw DataError(path, 0, 0, "cannot read the file: " + errno_text(err));
      }
      if (n == 0) break;
      out.resize(std::max<std::size_t>(65536, 2 * out.size()));
      std::memcpy(out.data() + have, probe, static_cast<std::size_t>(n));
      have += static_cast<std::size_t>(n);
      continue;
    }
    const ssize_t n = ::read(fd, out.data() + have, out.size() - have);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      throw DataError(path, 0, 0, "cannot read the file: " + errno_text(err));
    }
    if (n == 0) break;
    have += static_cast<std::size_t>(n);
  }
  out.resize(have);
  return out;
}

namespace {

/// True when the two paths name the same file: equal weakly_canonical paths (so
/// `./a.csv`, `dir/../a.csv` and symbolic links agree) or, when both exist,
/// std::filesystem::equivalent (which also catches hard links).
bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec_a, ec_b;
  const fs::path a_canon = fs::weakly_canonical(fs::path(a), ec_a);
  const fs::path b_canon = fs::weakly_canonical(fs::path(b), ec_b);
  if (!ec_a && !ec_b && a_canon == b_canon) return true;
  std::error_code ec_eq;
  return fs::equivalent(fs::path(a), fs::path(b), ec_eq) && !ec_eq;
}

}  // namespace

void refuse_to_overwrite_input(const std::string& out, const std::vector<std::string>& inputs) {
  for (const auto& in : inputs)
    if (same_file(out, in))
      throw std::invalid_argument("refusing to overwrite input file '" + in + "' with output '" + out +
                                  "': choose another output path");
}

void check_output_paths(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs,
                        bool replace_existing, const std::string& how_to_replace) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const std::string& out = outputs[i];
    if (out.empty()) continue;
    refuse_to_overwrite_input(out, inputs);
    for (std::size_t j = 0; j < i; ++j)
      if (!outputs[j].empty() && same_file(out, outputs[j]))
        throw OutputConflictError("two outputs name the same file ('" + outputs[j] + "' and '" + out +
                                    "'): one would replace the other");
    std::error_code ec;
    if (!replace_existing && fs::exists(fs::symlink_status(fs::path(out), ec)))
      throw std::invalid_argument("output file '" + out + "' already exists; not replacing it" +
                                  (how_to_replace.empty() ? std::string() : ": " + how_to_replace));
  }
}

}  // namespace sysid
