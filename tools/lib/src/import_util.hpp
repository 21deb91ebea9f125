// Small text-parsing helpers of the importers (private to tools/lib).
#pragma once

#include <cstdint>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

namespace tools::import_util {

std::string_view trim(std::string_view s);
/// Fields separated by sep (empty fields kept).
std::vector<std::string_view> split(std::string_view s, char sep);
/// Whitespace-separated tokens.
std::vector<std::string_view> split_ws(std::string_view s);
/// The whole (trimmed) field as a number; "nan"/"inf" parse (callers check finiteness).
bool parse_double(std::string_view s, double& v);
bool parse_int(std::string_view s, std::int64_t& v);
/// A Fortran number with a D exponent (RINEX): ".344484578818D-03".
bool parse_fortran_double(std::string_view s, double& v);
/// std::getline that also says whether the line ended with '\n' (false for a last line cut off).
bool getline_counted(std::istream& in, std::string& line, bool& terminated);
std::vector<std::uint8_t> read_file_bytes(const std::string& path);

}  // namespace tools::import_util
