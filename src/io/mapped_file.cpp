// Implementation of io/mapped_file.hpp (method there).
#include "sysid/io/mapped_file.hpp"

#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sysid/io/atomic_file.hpp"

namespace sysid {

MappedFile::MappedFile(const std::string& path) {
  const int fd = open_for_reading(path);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }  // a mapping outlives its descriptor
  } closer{fd};
  struct stat st {};
  const bool regular = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0;
  if (regular) {
    void* map = ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
    if (map != MAP_FAILED) {
      m_map = map;
      m_map_size = static_cast<std::size_t>(st.st_size);
      ::madvise(m_map, m_map_size, MADV_SEQUENTIAL);
      m_text = std::string_view(static_cast<const char*>(m_map), m_map_size);
      return;
    }
  }
  // Not mappable: read from the same descriptor (a FIFO opened twice would wait
  // for a second writer), with read_whole_file's messages for directories and read errors.
  m_owned = read_whole_descriptor(fd, path);
  m_text = m_owned;
}

MappedFile::~MappedFile() {
  if (m_map) ::munmap(m_map, m_map_size);
}

void MappedFile::release(const char* begin, const char* end) {
  if (!m_map || end <= begin) return;
  const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  const auto first = (static_cast<std::size_t>(begin - m_text.data()) + page - 1) / page * page;
  const auto last = static_cast<std::size_t>(end - m_text.data()) / page * page;
  if (last > first) ::madvise(static_cast<char*>(m_map) + first, last - first, MADV_DONTNEED);
}

}  // namespace sysid
