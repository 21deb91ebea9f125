// One validator for every floating-point option of the CLI (docs/faults.md, "Numeric options").
#pragma once

#include <CLI/CLI.hpp>

namespace tools {

/// Walks app and every (sub)command below it and attaches a finite-number check to each option
/// whose type is floating point (CLI11's type name "FLOAT", vectors of them included): "nan",
/// "inf", "-infinity", "1e999" (overflows to infinity) are refused at parse time with the option's
/// name, before any command runs. Call after every option is declared.
void require_finite_numbers(CLI::App& app);

/// The check itself (exposed for the tests): empty for a finite or non-numeric string.
std::string finite_number_problem(const std::string& text);

}  // namespace tools
