#include "numeric_options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

namespace tools {

std::string finite_number_problem(const std::string& text) {
  const char* b = text.c_str();
  char* e = nullptr;
  const double v = std::strtod(b, &e);
  if (e == b) return {};  // not a number at all: the option's own conversion reports it
  if (!std::isfinite(v)) return "not a finite number: '" + text + "' (NaN and infinities are not accepted)";
  return {};
}

std::string integer_problem(const std::string& text, bool is_unsigned) {
  std::size_t i = 0;
  const bool negative = !text.empty() && text[0] == '-';
  if (!text.empty() && (text[0] == '-' || text[0] == '+')) i = 1;
  const std::string digits = text.substr(i);
  if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos)
    return "not a decimal integer: '" + text + "'";
  if (digits.size() > 1 && digits[0] == '0')
    return "'" + text + "' has a leading zero (write the decimal value without it; it is not read as octal)";
  if (is_unsigned && negative && digits != "0") return "'" + text + "' is negative (the option takes values >= 0)";
  errno = 0;
  char* e = nullptr;
  if (is_unsigned)
    (void)std::strtoull(digits.c_str(), &e, 10);
  else
    (void)std::strtoll(text.c_str(), &e, 10);
  if (errno == ERANGE)
    return "'" + text + "' does not fit in 64 bits (" + std::string(is_unsigned ? "0 .. 18446744073709551615" :
                                                                     "-9223372036854775808 .. 9223372036854775807") +
           "); it is refused, not clamped";
  return {};
}

std::string utf8_problem(const std::string& text) {
  try {
    (void)nlohmann::json(text).dump();  // the rule of every JSON output the commands write
    return {};
  } catch (const nlohmann::json::type_error& e) {
    std::string shown;
    for (unsigned char c : text) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", c);
      shown += (c >= 0x20 && c < 0x7F) ? std::string(1, static_cast<char>(c)) : std::string(hex);
    }
    const std::string why = e.what();  // "[json.exception.type_error.316] invalid UTF-8 byte at index 7: 0xE9"
    const std::size_t at = why.find("] ");
    return "'" + shown + "' is not valid UTF-8 (" + (at == std::string::npos ? why : why.substr(at + 2)) +
           "); sdins records its inputs and outputs by name in JSON (summaries, sidecars), which must be UTF-8: "
           "rename the file or use a symbolic link with a UTF-8 name";
  }
}

const CLI::Validator& positive() {
  static const CLI::Validator v(
      [](std::string& s) -> std::string {
        char* e = nullptr;
        const double x = std::strtod(s.c_str(), &e);
        if (e == s.c_str() || *e != '\0') return "not a number: '" + s + "'";
        if (!(x > 0.0)) return "'" + s + "' is not positive (the value must be > 0)";
        return {};
      },
      "> 0", "POSITIVE");
  return v;
}

void require_valid_values(CLI::App& app) {
  // No descriptions: help texts unchanged.
  static const CLI::Validator finite([](std::string& s) { return finite_number_problem(s); }, "", "FINITE");
  static const CLI::Validator integer([](std::string& s) { return integer_problem(s, false); }, "", "INT64");
  static const CLI::Validator uinteger([](std::string& s) { return integer_problem(s, true); }, "", "UINT64");
  static const CLI::Validator utf8([](std::string& s) { return utf8_problem(s); }, "", "UTF8");
  for (CLI::Option* o : app.get_options()) {
    const std::string t = o->get_type_name();  // "FLOAT", "INT", "UINT" or "FLOAT:<validator>" ...
    if (t.rfind("FLOAT", 0) == 0)
      o->check(finite);
    else if (t.rfind("UINT", 0) == 0)
      o->check(uinteger);
    else if (t.rfind("INT", 0) == 0)
      o->check(integer);
    else if (t.rfind("TEXT", 0) == 0)
      o->check(utf8);
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) require_valid_values(*sub);
}

}  // namespace tools
