#include "tools/output_file.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace tools {

void require_distinct(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs) {
  const std::string why = hal::check_outputs(outputs, inputs);
  if (!why.empty()) throw std::runtime_error(why);
}

TextOutput::TextOutput(const std::string& path) {
  if (!f_.open(path)) throw std::runtime_error("cannot write " + f_.error());
}

void TextOutput::commit() {
  if (!f_.commit()) throw std::runtime_error("cannot write " + f_.error());
}

void write_text_file(const std::string& path, std::string_view content) {
  TextOutput out(path);
  out.os() << content;
  out.commit();
}

void write_json_file(const std::string& path, const nlohmann::json& j) { write_text_file(path, j.dump(2) + "\n"); }

namespace {
namespace fs = std::filesystem;

/// path relative to dir when it lies inside it (lexically, after making both absolute), else "".
std::string relative_inside(const fs::path& path, const fs::path& dir) {
  const fs::path rel = fs::absolute(path).lexically_normal().lexically_relative(fs::absolute(dir).lexically_normal());
  if (rel.empty() || rel.is_absolute() || *rel.begin() == "..") return {};
  return rel.string();
}

/// A manifest entry is a plain relative name inside the directory (never "..", never absolute).
bool safe_entry(const std::string& name) {
  const fs::path p(name);
  if (name.empty() || p.is_absolute()) return false;
  for (const fs::path& part : p)
    if (part == ".." || part == ".") return false;
  return true;
}
}  // namespace

RunDirectory::RunDirectory(const std::string& dir) : dir_(dir), first_output_(hal::committed_outputs().size()) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create the directory " + dir + ": " + ec.message());
  if (!fs::is_directory(dir, ec)) throw std::runtime_error(dir + ": not a directory");
  // docs/faults.md: two runs into one directory would remove each other's outputs as stale.
  lock_fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (lock_fd_ < 0) throw std::runtime_error("cannot open the directory " + dir + ": " + std::strerror(errno));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw std::runtime_error(e == EWOULDBLOCK ? dir + ": another sdins run is writing into this directory; wait for it "
                                                      "or use another directory"
                                              : "cannot lock the directory " + dir + ": " + std::strerror(e));
  }
  try {
    const std::string manifest = path(kManifest);
    if (fs::exists(fs::symlink_status(manifest, ec))) {
      try {
        std::ifstream in(manifest);
        const nlohmann::json j = nlohmann::json::parse(in);
        for (const auto& f : j.at("files"))
          if (f.is_string() && safe_entry(f.get<std::string>())) previous_.push_back(f.get<std::string>());
      } catch (const std::exception& e) {
        throw std::runtime_error(manifest + ": not a readable sdins output manifest (" + e.what() +
                                 "); remove it (the files it listed are then left alone) or use another directory");
      }
    }
    const std::string marker = path(kMarker);
    if (std::remove(marker.c_str()) != 0 && errno != ENOENT)
      throw std::runtime_error("cannot remove the previous run's " + marker + ": " + std::strerror(errno));
  } catch (...) {
    ::close(lock_fd_);  // the destructor does not run for a constructor that throws
    throw;
  }
}

RunDirectory::~RunDirectory() {
  // A run that did not finish (an error, SIGINT) names no outputs, but what it wrote is the tool's:
  // listed with the previous run's, so that the next complete run removes what it does not rewrite.
  if (!finished_) {
    std::vector<std::string> files = previous_;
    for (const std::string& f : outputs())
      if (std::find(files.begin(), files.end(), f) == files.end()) files.push_back(f);
    if (files != previous_) {
      try {
        write_manifest(files);
      } catch (const std::exception&) {
        // the manifest stays as it was: those files are then left alone, never removed on a guess
      }
    }
  }
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

void RunDirectory::write_manifest(const std::vector<std::string>& files) const {
  write_json_file(path(kManifest), {{"format", "sdins-run-outputs"},
                                    {"note", "files sdins runs wrote into this directory; the next complete run "
                                             "removes those it does not write again"},
                                    {"files", files}});
}

std::string RunDirectory::path(const std::string& name) const { return (fs::path(dir_) / name).string(); }

std::vector<std::string> RunDirectory::outputs() const {
  const std::vector<std::string> all = hal::committed_outputs();
  std::vector<std::string> mine;
  for (std::size_t i = first_output_; i < all.size(); ++i) {
    const std::string rel = relative_inside(all[i], dir_);
    if (rel.empty() || rel == kMarker || rel == kManifest) continue;
    if (std::find(mine.begin(), mine.end(), rel) == mine.end()) mine.push_back(rel);
  }
  std::sort(mine.begin(), mine.end());
  return mine;
}

void RunDirectory::finish(nlohmann::json summary) {
  const std::vector<std::string> mine = outputs();
  std::vector<std::string> kept_stale;  // could not be removed: listed again, tried next time
  for (const std::string& f : previous_) {
    if (f == kMarker || f == kManifest || std::find(mine.begin(), mine.end(), f) != mine.end()) continue;
    if (std::find(removed_.begin(), removed_.end(), f) != removed_.end()) continue;
    const std::string p = path(f);
    if (::unlink(p.c_str()) == 0 || errno == ENOENT) {
      removed_.push_back(f);
    } else {
      std::fprintf(stderr, "sdins: warning: cannot remove the previous run's %s: %s\n", p.c_str(), std::strerror(errno));
      kept_stale.push_back(f);
    }
  }
  std::vector<std::string> listed = mine;
  listed.insert(listed.end(), kept_stale.begin(), kept_stale.end());
  listed.push_back(kMarker);
  write_manifest(listed);
  previous_ = listed;
  finished_ = true;
  summary["outputs"] = mine;
  write_json_file(path(kMarker), summary);
}

}  // namespace tools
