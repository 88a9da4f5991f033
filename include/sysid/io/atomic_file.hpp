#pragma once
/// @file
/// Purpose: whole-file I/O with the guarantees the CLI promises ("nothing is ever
/// half-written"): a file is replaced in one step or not at all, and an output is
/// never allowed to clobber one of the inputs it was computed from.
///
/// Method: POSIX write-to-temporary, fsync, rename(2) over the target. rename is
/// atomic within one file system, so a reader (or a crash) sees either the old or
/// the new contents, never a mixture; the temporary lives in the target's own
/// directory so the rename never crosses a file system.
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

/// Purpose: replace (or create) `path` with `contents` atomically.
///
/// Method: on Linux the contents go to an unnamed file in the target's directory
/// (open(2) with O_TMPFILE), so a process killed while writing, even by SIGKILL,
/// leaves no trace; once complete and fsynced it gets the name
/// `.<name>.tmp.<pid>.<random>` (linkat) and is at once renamed over the target.
/// Where O_TMPFILE is unavailable that named temporary is written directly (created
/// with O_EXCL, so two writers never share a temporary). Either way the file gets
/// the mode of the existing target (if any) and the directory is fsynced after the
/// rename. A symbolic link as target is followed: the file it points to is
/// replaced, the link stays.
///
/// Errors: throws sysid::DataError (file = path) naming the cause (directory
/// missing, permission denied, disk full, target is a directory ...). On every
/// error the temporary is removed and the old target, if any, is untouched.
/// Throws std::invalid_argument if `path` is empty.
void write_file_atomically(const std::string& path, const std::string& contents);

/// Purpose: read a whole file into memory in one read (the parsers then work on
/// one contiguous buffer).
///
/// Errors: sysid::DataError (file = path) when the file is missing, unreadable or a
/// directory.
std::string read_whole_file(const std::string& path);

/// open(2) for reading (close-on-exec); sysid::DataError (file = path) naming the
/// cause when that fails. The caller closes the descriptor.
int open_for_reading(const std::string& path);

/// read_whole_file on a descriptor already open for reading (left open), e.g. a
/// FIFO that must not be opened twice; `path` names it in messages.
std::string read_whole_descriptor(int fd, const std::string& path);

/// Purpose: refuse an output path that is one of the inputs, before any work is
/// done (e.g. `sysid simulate ... log.csv --out log.csv`).
///
/// Method: compares std::filesystem::weakly_canonical paths (so `./a.csv`,
/// `dir/../a.csv` and symbolic links resolve to the same name), and, when both
/// exist, std::filesystem::equivalent (which also catches hard links).
///
/// Errors: std::invalid_argument naming both paths when `out` resolves to an input.
void refuse_to_overwrite_input(const std::string& out, const std::vector<std::string>& inputs);

/// Two outputs of one run that name the same file: a contradiction in how the run
/// was asked for (the CLI reports it as a usage error), not a problem of the data.
struct OutputConflictError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// Purpose: check every file a run is going to write, before any work is done, so
/// that a run either writes all its outputs or fails without touching anything.
///
/// Method: empty paths (an output option not given) are skipped. Each output is
/// refused when it resolves to an input (refuse_to_overwrite_input), when two
/// outputs resolve to the same file (one would silently replace the other), and,
/// unless `replace_existing`, when it already exists. The check is advisory against
/// other processes (a file created between the check and the write is still
/// replaced atomically, never mixed).
///
/// Errors: OutputConflictError for two outputs naming one file; otherwise
/// std::invalid_argument naming the path; for an existing output the message ends
/// with `how_to_replace` (e.g. "pass --force to replace it").
void check_output_paths(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs,
                        bool replace_existing, const std::string& how_to_replace = "");

}  // namespace sysid
