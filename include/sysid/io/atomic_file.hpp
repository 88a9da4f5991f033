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
#include <string>
#include <vector>

namespace sysid {

/// Purpose: replace (or create) `path` with `contents` atomically.
///
/// Method: writes `.<name>.tmp.<pid>.<random>` beside the target (created with
/// O_EXCL, so two writers never share a temporary), fsyncs it, gives it the mode of
/// the existing target (if any), renames it over the target and fsyncs the
/// directory. A symbolic link as target is followed: the file it points to is
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

/// Purpose: refuse an output path that is one of the inputs, before any work is
/// done (e.g. `sysid simulate ... log.csv --out log.csv`).
///
/// Method: compares std::filesystem::weakly_canonical paths (so `./a.csv`,
/// `dir/../a.csv` and symbolic links resolve to the same name), and, when both
/// exist, std::filesystem::equivalent (which also catches hard links).
///
/// Errors: std::invalid_argument naming both paths when `out` resolves to an input.
void refuse_to_overwrite_input(const std::string& out, const std::vector<std::string>& inputs);

}  // namespace sysid
