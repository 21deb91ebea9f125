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

/// A directory of results (docs/faults.md, "run directories"). The outputs of a run are exactly the
/// files its summary.json names ("outputs"): every file this process put in place inside the
/// directory after the RunDirectory was created (hal::committed_outputs(), figures of the plot
/// scripts included). A manifest (.sdins-outputs.json) lists what the last complete run wrote; the
/// next run removes those of them it did not write again (stale results of a run with more models).
/// Files the tool did not write (not in a manifest) are never touched.
class RunDirectory {
 public:
  /// Creates the directory, reads the previous run's manifest and removes its summary.json (the
  /// completion marker).
  /// Takes an exclusive lock on the directory (flock): a second run into the same directory while
  /// this one is alive is refused, naming it.
  explicit RunDirectory(const std::string& dir);
  ~RunDirectory();
  RunDirectory(const RunDirectory&) = delete;
  RunDirectory& operator=(const RunDirectory&) = delete;
  std::string path(const std::string& name) const;
  /// Removes the previous run's outputs this run did not write, writes the manifest, then
  /// summary.json last, atomically (with "outputs" added): the run is complete. May be called again
  /// after more outputs (figures drawn from the summary): the summary and the manifest are renewed.
  void finish(nlohmann::json summary);
  const std::string& dir() const { return dir_; }
  /// This run's outputs so far, relative to the directory, sorted (summary.json excluded).
  std::vector<std::string> outputs() const;
  /// Files of the previous run removed by finish() (relative names).
  const std::vector<std::string>& removed() const { return removed_; }
  static constexpr const char* kMarker = "summary.json";
  static constexpr const char* kManifest = ".sdins-outputs.json";

 private:
  std::string dir_;
  std::size_t first_output_ = 0;       ///< index into hal::committed_outputs() at creation
  std::vector<std::string> previous_;  ///< the previous manifest's files
  std::vector<std::string> removed_;
  int lock_fd_ = -1;  ///< the directory, flock()ed while the run lasts
  bool finished_ = false;
  void write_manifest(const std::vector<std::string>& files) const;
};

}  // namespace tools
