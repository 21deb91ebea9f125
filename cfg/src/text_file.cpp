#include "cfg/text_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

namespace cfg {

std::optional<std::string> read_text_file(const std::string& path) {
  // Bounded (docs/faults.md): only a regular file of at most kMaxTextFileBytes is read, so a
  // device such as /dev/zero, a FIFO or a directory is refused instead of read for ever.
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return std::nullopt;
  if (static_cast<unsigned long long>(st.st_size) > kMaxTextFileBytes) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::string text;
  text.reserve(static_cast<std::size_t>(st.st_size));
  char buf[65536];
  while (in.read(buf, sizeof(buf)) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxTextFileBytes) return std::nullopt;  // grew while being read
  }
  if (in.bad()) return std::nullopt;
  return text;
}

std::string text_file_problem(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::strerror(errno);
  if (S_ISDIR(st.st_mode)) return "is a directory";
  if (!S_ISREG(st.st_mode)) return "not a regular file (a device, FIFO or socket may never end)";
  if (static_cast<unsigned long long>(st.st_size) > kMaxTextFileBytes)
    return "larger than the text-file limit of " + std::to_string(kMaxTextFileBytes >> 20) + " MiB";
  return "cannot read";
}

}  // namespace cfg
