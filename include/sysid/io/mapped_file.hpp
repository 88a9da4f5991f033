#pragma once
/// @file
/// Purpose: read a large file for one sequential pass without holding all of it
/// in memory: a parser walks the text front to back and hands back what it has
/// finished with, so the file's bytes never sit in memory beside all of the
/// parsed result (a 191 MB log of 10^6 x 17 values: peak 345 -> ~150 MB).
///
/// Method: a regular, non-empty file is mapped read-only (mmap(2), MAP_PRIVATE,
/// MADV_SEQUENTIAL); `release(begin, end)` drops the whole pages inside [begin, end)
/// from the process (madvise MADV_DONTNEED: a later access reads them again from the page
/// cache, so releasing too early costs time, never correctness). Anything else
/// (a pipe, a device, an empty file, a failed mapping) is read whole into memory
/// from the same descriptor (read_whole_descriptor), where release does nothing.
///
/// Errors: sysid::DataError (file = path) when the file is missing, unreadable or
/// a directory. A mapped file truncated by another process while it is read ends
/// the reader with SIGBUS (mmap semantics); logs being appended to are safe (the
/// mapping covers the size at open).
#include <cstddef>
#include <string>
#include <string_view>

namespace sysid {

class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  /// The file's bytes (valid while the object lives; released pages read back transparently).
  std::string_view text() const { return m_text; }
  /// Drops the pages wholly inside [begin, end) (pointers into text()) from memory.
  void release(const char* begin, const char* end);
  /// Whether the text is mapped (release has an effect) rather than read whole.
  bool mapped() const { return m_map != nullptr; }

 private:
  void* m_map = nullptr;
  std::size_t m_map_size = 0;
  std::string m_owned;  ///< the text when not mapped
  std::string_view m_text;
};

}  // namespace sysid
