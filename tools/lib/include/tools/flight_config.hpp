// The flight configuration the commands fly with: config/default.toml (shipped in the data
// directory, sim/data_dir.hpp), and a data set's file on top (sim::load_filter_config). The one
// place where a harness departs from it is the Monte Carlo's scenario overlay (montecarlo.hpp,
// executive_config), documented in config/README.md.
#pragma once

#include <string>

#include "sim/filter_config.hpp"

namespace tools {

/// The shipped file alone, read once per process. Throws std::runtime_error with the file's error.
const sim::FilterConfig& shipped_filter_config();

/// The shipped file with `path` on top (empty: the shipped file alone). Throws std::runtime_error
/// with the file's error.
sim::FilterConfig filter_config(const std::string& path);

/// Throws std::runtime_error "<what>: gnss.source = "...", but <why>; use "raw"" unless the
/// configuration flies raw receiver epochs (the commands whose input carries no solutions).
void require_raw_gnss(const sim::FilterConfig& f, const std::string& what, const std::string& why);

}  // namespace tools
