// The output-file discipline of the sdins commands (docs/faults.md), as throwing helpers over
// hal::OutputFile (hal/output_file.hpp) for the tools' front ends:
//  - require_distinct(): an output that is an input (or inside an input directory, or another
//    output) is refused before anything is opened for writing;
//  - TextOutput / write_text_file(): a temporary file beside the target, renamed over it when
//    complete; every write, flush, fsync, close and rename checked; std::runtime_error naming the
//    file and the errno text on failure, with the target left as it was;
//  - RunDirectory: a directory of results (montecarlo, paper, analyze, diagnose --report) whose
//    completion marker is summary.json, removed when a run starts and written last (atomically) when
//    it has finished: a directory without summary.json holds no complete run.
#pragma once

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "hal/output_file.hpp"

namespace tools {

/// Throws std::runtime_error when an output is an input, lies inside an input directory or is
/// another output (hal::check_outputs). Empty paths are ignored.
void require_distinct(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

class TextOutput {
 public:
  /// Opens the temporary file; throws when it cannot be created.
  explicit TextOutput(const std::string& path);
  std::ostream& os() { return f_.stream(); }
  /// Throws (with the file and errno) when any write failed or the file cannot be put in place.
  void commit();
  const std::string& path() const { return f_.path(); }

 private:
  hal::OutputFile f_;
};

/// The whole file at once through TextOutput.
void write_text_file(const std::string& path, std::string_view content);
/// JSON (dump(2) and a newline).
void write_json_file(const std::string& path, const nlohmann::json& j);

class RunDirectory {
 public:
  /// Creates the directory and removes a previous run's summary.json (the completion marker).
  explicit RunDirectory(const std::string& dir);
  std::string path(const std::string& name) const;
  /// Writes summary.json last, atomically: the run is complete.
  void finish(const nlohmann::json& summary) const;
  const std::string& dir() const { return dir_; }
  static constexpr const char* kMarker = "summary.json";

 private:
  std::string dir_;
};

}  // namespace tools
