#include "hal/input_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

namespace hal {

std::string check_input_file(const std::string& path, std::uint64_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return path + ": " + std::strerror(errno);
  if (!S_ISREG(st.st_mode)) {
    const char* kind = S_ISDIR(st.st_mode)    ? "a directory"
                       : S_ISCHR(st.st_mode)  ? "a character device"
                       : S_ISBLK(st.st_mode)  ? "a block device"
                       : S_ISFIFO(st.st_mode) ? "a FIFO"
                       : S_ISSOCK(st.st_mode) ? "a socket"
                                              : "not a regular file";
    return path + ": not a regular file (" + kind + "): refusing an input that may never end";
  }
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes)
    return path + ": " + std::to_string(st.st_size) + " bytes, above this reader's limit of " +
           std::to_string(max_bytes) + " bytes";
  return {};
}

}  // namespace hal
