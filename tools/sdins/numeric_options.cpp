#include "numeric_options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace tools {

std::string finite_number_problem(const std::string& text) {
  const char* b = text.c_str();
  char* e = nullptr;
  const double v = std::strtod(b, &e);
  if (e == b) return {};  // not a number at all: the option's own conversion reports it
  if (!std::isfinite(v)) return "not a finite number: '" + text + "' (NaN and infinities are not accepted)";
  return {};
}

void require_finite_numbers(CLI::App& app) {
  static const CLI::Validator finite(
      [](std::string& s) { return finite_number_problem(s); }, "", "FINITE");  // no description: help texts unchanged
  for (CLI::Option* o : app.get_options())
    if (o->get_type_name().rfind("FLOAT", 0) == 0) o->check(finite);  // "FLOAT" or "FLOAT:<validator>"
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) require_finite_numbers(*sub);
}

}  // namespace tools
