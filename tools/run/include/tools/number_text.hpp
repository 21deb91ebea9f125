// One number as text through a printf format: how the reports, the Markdown tables and the
// messages of the tools write a value ("%.3f" -> "0.125"). One definition for every tools library
// and the command line (it had been written out again in eight files).
#pragma once

#include <string>

namespace tools {

/// printf_format holds exactly one conversion of a double (%f, %g, %e with flags, width and
/// precision); the text is cut at 63 characters.
std::string fmt(const char* printf_format, double v);

}  // namespace tools
