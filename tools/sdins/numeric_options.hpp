// One validator for every option value of the CLI (docs/faults.md, "Numeric options", "Text options").
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace tools {

/// Walks app and every (sub)command below it and attaches one check to each numeric option:
///  - floating point (CLI11's type name "FLOAT", vectors of them included): "nan", "inf",
///    "-infinity", "1e999" (overflows to infinity) are refused;
///  - integers ("INT", "UINT"): only decimal digits with an optional sign are accepted, within
///    64 bits: "99999999999999999999" (CLI11 would clamp it to 2^63-1), "-1" for an unsigned option
///    (CLI11 would wrap it to 2^64-1), "010" (CLI11 would read octal 8) and "0x10" are refused.
///  - text ("TEXT": file names, bus names, ...): must be valid UTF-8 (every JSON output names its
///    inputs and outputs; a name that cannot be written there is refused before anything is written,
///    instead of a JSON library's exception after the log and before its sidecar).
/// Every refusal names the option and the value, at parse time, before any command runs. Call after
/// every option is declared.
void require_valid_values(CLI::App& app);

/// The checks themselves (exposed for the tests): empty for an acceptable or non-numeric string.
std::string finite_number_problem(const std::string& text);
std::string integer_problem(const std::string& text, bool is_unsigned);
std::string utf8_problem(const std::string& text);

/// A CLI11 validator for a value that must be > 0 ("a timeout that is not positive is refused").
const CLI::Validator& positive();

}  // namespace tools
