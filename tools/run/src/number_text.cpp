#include "tools/number_text.hpp"

#include <cstdio>

namespace tools {

std::string fmt(const char* printf_format, double v) {
  char b[64];
  std::snprintf(b, sizeof b, printf_format, v);
  return b;
}

}  // namespace tools
