#include "tools/output_file.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
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

RunDirectory::RunDirectory(const std::string& dir) : dir_(dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create the directory " + dir + ": " + ec.message());
  if (!std::filesystem::is_directory(dir, ec)) throw std::runtime_error(dir + ": not a directory");
  const std::string marker = path(kMarker);
  if (std::remove(marker.c_str()) != 0 && errno != ENOENT)
    throw std::runtime_error("cannot remove the previous run's " + marker + ": " + std::strerror(errno));
}

std::string RunDirectory::path(const std::string& name) const { return (std::filesystem::path(dir_) / name).string(); }

void RunDirectory::finish(const nlohmann::json& summary) const { write_json_file(path(kMarker), summary); }

}  // namespace tools
