// The one wiring list (tools/harness_wiring.hpp) against README.md's harness table and against
// the code: every entry's file drives the flight application with the named source and driver,
// and no other file of tools/, hal/ or fsw/baremetal calls fsw::drive.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tools/harness_wiring.hpp"

namespace {

const std::filesystem::path kSource = SDINS_TEST_SOURCE_DIR;

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Whether needle occurs in the code of text (outside // comments).
bool in_code(const std::string& text, const std::string& needle) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t at = line.find(needle);
    if (at != std::string::npos && line.substr(0, at).find("//") == std::string::npos) return true;
  }
  return false;
}

/// The identifier after the last "::" (what the file names, with or without its namespace).
std::string last_name(std::string_view qualified) {
  const std::size_t k = qualified.rfind("::");
  return std::string(k == std::string_view::npos ? qualified : qualified.substr(k + 2));
}

/// One README row of an entry (what the README table must hold, in the list's order).
std::string row(const tools::HarnessWiring& w) {
  return "| " + std::string(w.harness) + " | `" + std::string(w.source) + "`: " + std::string(w.feeds) + " | `" +
         std::string(w.driver) + "` (" + std::string(w.layouts) + ") | " + std::string(w.observers) + " |";
}

/// The table rows (after the header and its separator) of the README section with this heading.
std::vector<std::string> readme_rows(const std::string& heading) {
  std::istringstream in(slurp(kSource / "README.md"));
  std::vector<std::string> rows;
  std::string line;
  bool in_section = false;
  int table_line = 0;
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0) {
      if (in_section) break;
      in_section = line == heading;
      continue;
    }
    if (!in_section) continue;
    if (line.rfind("|", 0) != 0) {
      if (table_line > 0) break;  // the first table of the section only
      continue;
    }
    if (++table_line > 2) rows.push_back(line);
  }
  return rows;
}

}  // namespace

TEST(HarnessWiring, ReadmeTableIsTheWiringList) {
  std::vector<std::string> want;
  std::string paste;
  for (const tools::HarnessWiring& w : tools::kHarnessWiring) {
    want.push_back(row(w));
    paste += row(w) + "\n";
  }
  EXPECT_EQ(readme_rows("## Architecture: one data path"), want)
      << "README.md's harness table must be tools/harness_wiring.hpp's list; its rows are:\n"
      << paste;
}

TEST(HarnessWiring, EveryEntryDrivesTheFlightApplicationAsListed) {
  for (const tools::HarnessWiring& w : tools::kHarnessWiring) {
    const std::filesystem::path p = kSource / w.file;
    ASSERT_TRUE(std::filesystem::exists(p)) << w.harness << ": no file " << w.file;
    const std::string text = slurp(p);
    EXPECT_TRUE(in_code(text, "fsw::drive(")) << w.file << " does not call fsw::drive";
    EXPECT_TRUE(in_code(text, last_name(w.source))) << w.file << " does not name its source " << w.source;
    EXPECT_TRUE(in_code(text, last_name(w.driver))) << w.file << " does not name its driver " << w.driver;
  }
}

TEST(HarnessWiring, NoHarnessOutsideTheList) {
  std::set<std::string> listed;
  for (const tools::HarnessWiring& w : tools::kHarnessWiring) listed.insert(std::string(w.file));
  for (const char* dir : {"tools", "hal", "fsw/baremetal"}) {
    for (const auto& e : std::filesystem::recursive_directory_iterator(kSource / dir)) {
      const std::string ext = e.path().extension().string();
      if (!e.is_regular_file() || (ext != ".cpp" && ext != ".hpp")) continue;
      if (!in_code(slurp(e.path()), "fsw::drive(")) continue;
      const std::string rel = std::filesystem::relative(e.path(), kSource).string();
      EXPECT_TRUE(listed.count(rel) == 1) << rel << " drives the flight application but is not in tools/harness_wiring.hpp";
    }
  }
}
