// sdins audit stack | timing: the flight-software audits of docs/audits.md.
//
//   stack   builds fsw/ in the stack-audit configuration (preset stack-audit: GCC, Release flags,
//           -fstack-usage -fcallgraph-info=su), checks the instrument on its fixtures, computes the
//           worst-case stack of every task over the call graph (tools/stack_audit.hpp) and the static
//           RAM of the fsw library (`size`). Exit status: 0 every task bounded and within budget,
//           3 some task over budget or unbounded, 1 the audit itself failed.
//   timing  flies a scenario through the executive of each layout and times every tick
//           (tools/timing_audit.hpp).
//   target  the Cortex-M7 image in QEMU against the host (docs/baremetal-qemu.md): runs
//           tests/e2e/target_qemu.sh with this sdins and the sdins_target built beside it.
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "commands.hpp"
#include "tools/output_file.hpp"
#include "fsw/executive.hpp"
#include "tools/stack_audit.hpp"
#include "tools/timing_audit.hpp"

namespace sdins {
namespace {

struct StackOptions {
  std::string json;
  long budget_bytes = 16 * 1024;
  std::string build_dir;  ///< empty: <source>/build/stack-audit (the preset's)
  std::string source_dir;  ///< empty: found by project_source_dir()
  bool no_build = false;
  int jobs = 2;
} stack_opt;

struct TimingOptions {
  ScenarioOptions scenario;
  std::string layouts = "Layout15,Layout24,Layout15Full,Layout24Full";
  std::string init = "track";
  std::string json;
} timing_opt;

struct TargetOptions {
  std::string json;
  std::string out_dir;
  std::string source_dir;  ///< empty: found by project_source_dir()
  double duration_s = 40.0;
} target_opt;

CLI::App* g_stack = nullptr;
CLI::App* g_timing = nullptr;
CLI::App* g_target = nullptr;

/// A directory that holds this project's sources (its CMakePresets.json with the stack-audit preset).
bool is_project_source(const std::filesystem::path& d) {
  std::ifstream in(d / "CMakePresets.json");
  if (!in) return false;
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str().find("\"stack-audit\"") != std::string::npos && std::filesystem::exists(d / "fsw");
}

/// The source tree the stack audit builds: --source-dir; else the current directory or one of its
/// parents when it is the project; else the source tree of the build tree sdins runs from (its
/// CMakeCache.txt, CMAKE_HOME_DIRECTORY). An installed sdins has neither: it needs --source-dir.
/// No source path is compiled into the binary.
std::string project_source_dir(const std::string& given) {
  namespace fs = std::filesystem;
  if (!given.empty()) {
    if (!is_project_source(given))
      throw std::runtime_error("--source-dir " + given + ": not the sdins source tree (no CMakePresets.json with "
                               "the stack-audit preset and fsw/)");
    return fs::absolute(given).lexically_normal().string();
  }
  std::error_code ec;
  for (fs::path d = fs::current_path(ec); !ec && !d.empty(); d = d.parent_path()) {
    if (is_project_source(d)) return d.string();
    if (d == d.root_path()) break;
  }
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    std::ifstream cache(exe.parent_path().parent_path() / "CMakeCache.txt");
    std::string line;
    const std::string key = "CMAKE_HOME_DIRECTORY:INTERNAL=";
    while (std::getline(cache, line))
      if (line.rfind(key, 0) == 0 && is_project_source(line.substr(key.size()))) return line.substr(key.size());
  }
  throw std::runtime_error("the stack audit builds fsw/ from the project's sources: run it inside the source tree "
                           "or give --source-dir DIR");
}

/// Runs a shell command, returns its standard output; throws when it fails.
std::string capture(const std::string& cmd) {
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen(cmd.c_str(), "r"), pclose);
  if (!p) throw std::runtime_error("cannot run: " + cmd);
  std::string out;
  std::array<char, 4096> buf{};
  std::size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), p.get())) > 0) out.append(buf.data(), n);
  const int rc = pclose(p.release());
  if (rc != 0) throw std::runtime_error("command failed (" + std::to_string(rc) + "): " + cmd);
  return out;
}

std::string tail_of_file(const std::string& path, std::size_t max_chars) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string s = ss.str();
  return s.size() > max_chars ? s.substr(s.size() - max_chars) : s;
}

void build_stack_audit(const std::string& src, const std::string& dir, int jobs) {
  const std::string log = dir + "/sdins-audit-build.log";
  std::filesystem::create_directories(dir);
  const std::string cmake = shell_quote(SDINS_CMAKE_COMMAND);
  const std::string cmd = cmake + " --preset stack-audit -S " + shell_quote(src) + " -B " + shell_quote(dir) +
                          " > " + shell_quote(log) + " 2>&1 && " + cmake + " --build " + shell_quote(dir) + " -j " +
                          std::to_string(jobs) + " >> " + shell_quote(log) + " 2>&1";
  std::fprintf(stderr, "sdins audit stack: building fsw/ in %s (log: %s)\n", dir.c_str(), log.c_str());
  if (std::system(cmd.c_str()) != 0)
    throw std::runtime_error("the stack-audit build failed; end of " + log + ":\n" + tail_of_file(log, 3000));
}

/// The compile command of fsw/src/ekf.cpp in the audit build (what the numbers are for).
std::string ekf_compile_command(const std::string& dir) {
  std::ifstream in(dir + "/compile_commands.json");
  if (!in) return "";
  const nlohmann::json cc = nlohmann::json::parse(in, nullptr, false);
  if (!cc.is_array()) return "";
  for (const auto& e : cc)
    if (e.value("file", "").find("fsw/src/ekf.cpp") != std::string::npos) return e.value("command", "");
  return "";
}

struct SizeTotals {
  long text = 0, data = 0, bss = 0;
};
/// Berkeley `size -t` of an archive: the (TOTALS) line.
SizeTotals size_totals(const std::string& archive) {
  const std::string out = capture("size -t --format=berkeley " + shell_quote(archive));
  std::stringstream ss(out);
  for (std::string line; std::getline(ss, line);) {
    if (line.find("(TOTALS)") == std::string::npos) continue;
    SizeTotals t;
    std::stringstream ls(line);
    if (ls >> t.text >> t.data >> t.bss) return t;
  }
  throw std::runtime_error("no (TOTALS) line in `size -t " + archive + "`:\n" + out);
}

using Aliases = std::vector<std::pair<std::string, std::string>>;

/// r with the layout types' spellings replaced by Layout15 ... in every name and reason.
tools::stack::TaskResult readable(tools::stack::TaskResult r, const Aliases& a) {
  for (auto& s : r.path) s.name = tools::stack::with_aliases(s.name, a);
  for (auto& s : r.unbounded_reasons) s = tools::stack::with_aliases(s, a);
  for (auto& f : r.findings) f.reason = tools::stack::with_aliases(f.reason, a);
  return r;
}

nlohmann::json task_json(const tools::stack::TaskResult& r, const Aliases& a) {
  nlohmann::json j;
  j["name"] = r.name;
  j["description"] = r.description;
  j["root"] = tools::stack::with_aliases(tools::stack::demangle(r.root), a);
  j["stack_bytes"] = r.stack_bytes;
  j["bounded"] = r.bounded;
  if (r.budget_bytes > 0) {
    j["budget_bytes"] = r.budget_bytes;
    j["within_budget"] = r.within_budget;
  }
  j["unbounded_reasons"] = r.unbounded_reasons;
  nlohmann::json f = nlohmann::json::array();
  for (const auto& fd : r.findings) {
    nlohmann::json chain = nlohmann::json::array();
    for (const auto& id : fd.via)
      chain.push_back(tools::stack::with_aliases(tools::stack::compact_name(tools::stack::demangle(id)), a));
    f.push_back({{"reason", fd.reason}, {"via", chain}});
  }
  j["unbounded_via"] = f;
  j["assumed_externals"] = r.assumed_externals;
  j["functions_reached"] = r.functions_reached;
  nlohmann::json path = nlohmann::json::array();
  for (const auto& s : r.path) {
    nlohmann::json p{{"function", s.name}, {"short", tools::stack::compact_name(s.name)}, {"frame_bytes", s.frame_bytes}};
    if (!s.note.empty()) p["note"] = s.note;
    path.push_back(p);
  }
  j["deepest_path"] = path;
  return j;
}

std::string shorten(const std::string& s, std::size_t n) { return s.size() <= n ? s : s.substr(0, n - 3) + "..."; }

int run_audit_stack() {
  namespace st = tools::stack;
  const bool need_src = stack_opt.build_dir.empty() || !stack_opt.no_build;
  const std::string src = need_src ? project_source_dir(stack_opt.source_dir) : std::string();
  const std::string dir = stack_opt.build_dir.empty() ? src + "/build/stack-audit"
                                                      : std::filesystem::absolute(stack_opt.build_dir).string();
  if (!stack_opt.no_build) build_stack_audit(src, dir, stack_opt.jobs);
  const st::BuildData b = st::load_build_dir(dir);
  const std::vector<std::string> diff = st::cross_check(b.graph, b.su);
  if (!diff.empty()) {
    std::string msg = ".su and .ci stack usage disagree:";
    for (std::size_t i = 0; i < diff.size() && i < 20; ++i) msg += "\n  " + diff[i];
    throw std::runtime_error(msg);
  }
  const std::vector<st::ExternalCost>& costs = st::external_costs();
  const long red_zone = st::kX86_64RedZoneBytes;  // the audit build is the host (x86-64) compiler
  const std::vector<st::SelfCheck> checks = st::self_check(b.graph, costs, red_zone);
  bool checks_ok = true;
  for (const auto& c : checks) checks_ok = checks_ok && c.pass;

  std::vector<st::TaskSpec> task_specs, function_specs;
  st::fsw_task_specs(b.graph, stack_opt.budget_bytes, red_zone, task_specs, function_specs);
  std::vector<st::TaskResult> tasks, functions;
  const Aliases aliases = st::layout_aliases(b.graph);
  for (const auto& s : task_specs) tasks.push_back(readable(st::analyse(b.graph, s, costs), aliases));
  for (const auto& s : function_specs) functions.push_back(readable(st::analyse(b.graph, s, costs), aliases));
  const SizeTotals sz = size_totals(dir + "/fsw/libsdins_fsw.a");

  bool all_ok = true;
  for (const auto& t : tasks) all_ok = all_ok && t.bounded && t.within_budget;

  // Console report.
  std::printf("stack audit of fsw/ (%s, %d .ci / %d .su files, %zu functions; .su and .ci agree)\n", dir.c_str(),
              b.ci_files, b.su_files, b.graph.functions.size());
  std::printf("instrument self-check on tests/stack/stack_fixtures.cpp:\n");
  for (const auto& c : checks)
    std::printf("  %-14s %-4s %s (%s)\n", c.fixture.c_str(), c.pass ? "ok" : "FAIL", c.expect.c_str(),
                shorten(c.detail, 200).c_str());
  std::printf("\n%-26s %10s %8s %8s  %s\n", "task", "stack [B]", "budget", "bounded", "result");
  for (const auto& t : tasks)
    std::printf("%-26s %10ld %8ld %8s  %s\n", t.name.c_str(), t.stack_bytes, t.budget_bytes, t.bounded ? "yes" : "NO",
                !t.bounded ? "UNBOUNDED" : t.within_budget ? "ok" : "OVER BUDGET");
  std::printf("\n%-26s %10s %8s\n", "function", "stack [B]", "bounded");
  for (const auto& f : functions)
    std::printf("%-26s %10ld %8s\n", f.name.c_str(), f.stack_bytes, f.bounded ? "yes" : "NO");
  std::printf("\nstatic RAM of libsdins_fsw.a: %ld B (.data %ld, .bss %ld; text+rodata %ld)\n", sz.data + sz.bss, sz.data,
              sz.bss, sz.text);
  std::printf("caller-owned state: Executive<Layout15> %zu B, <Layout24> %zu B, <Layout15Full> %zu B, <Layout24Full> %zu B\n",
              sizeof(fsw::Executive<fsw::Layout15>), sizeof(fsw::Executive<fsw::Layout24>),
              sizeof(fsw::Executive<fsw::Layout15Full>), sizeof(fsw::Executive<fsw::Layout24Full>));
  for (const auto& t : tasks) {
    if (t.bounded && t.within_budget) continue;
    std::printf("\n%s: %ld B (%s)\n", t.name.c_str(), t.stack_bytes, t.bounded ? "over budget" : "unbounded");
    for (const auto& fd : t.findings) {
      std::printf("  unbounded: %s\n", shorten(fd.reason, 220).c_str());
      std::string chain;
      for (const auto& id : fd.via)
        chain += (chain.empty() ? "" : " -> ") + shorten(st::with_aliases(st::compact_name(st::demangle(id)), aliases), 90);
      std::printf("    via %s\n", chain.c_str());
    }
    std::printf("  deepest path:\n");
    for (const auto& s : t.path)
      std::printf("    %8ld  %s%s\n", s.frame_bytes, shorten(s.name, 160).c_str(),
                  s.note.empty() ? "" : ("  [" + s.note + "]").c_str());
  }

  if (!stack_opt.json.empty()) {
    nlohmann::json j;
    j["tool"] = "sdins audit stack";
    j["build_dir"] = dir;
    j["compile_command"] = ekf_compile_command(dir);
    j["budget_bytes"] = stack_opt.budget_bytes;
    j["red_zone_bytes"] = red_zone;
    j["static_ram_bytes"] = sz.data + sz.bss;
    j["static_ram"] = {{"data", sz.data}, {"bss", sz.bss}, {"text", sz.text}, {"archive", dir + "/fsw/libsdins_fsw.a"}};
    j["objects"] = nlohmann::json::array(
        {{{"name", "fsw::Executive<Layout15>"}, {"bytes", sizeof(fsw::Executive<fsw::Layout15>)}},
         {{"name", "fsw::Executive<Layout24>"}, {"bytes", sizeof(fsw::Executive<fsw::Layout24>)}},
         {{"name", "fsw::Executive<Layout15Full>"}, {"bytes", sizeof(fsw::Executive<fsw::Layout15Full>)}},
         {{"name", "fsw::Executive<Layout24Full>"}, {"bytes", sizeof(fsw::Executive<fsw::Layout24Full>)}}});
    nlohmann::json jt = nlohmann::json::array(), jf = nlohmann::json::array();
    for (const auto& t : tasks) jt.push_back(task_json(t, aliases));
    for (const auto& f : functions) jf.push_back(task_json(f, aliases));
    j["tasks"] = jt;
    j["functions"] = jf;
    j["all_within_budget"] = all_ok;
    nlohmann::json jc = nlohmann::json::array();
    for (const auto& c : checks) jc.push_back({{"fixture", c.fixture}, {"expect", c.expect}, {"pass", c.pass}, {"detail", c.detail}});
    j["self_check"] = jc;
    j["cross_check"] = {{"ci_records", b.graph.frame_records.size()}, {"su_records", b.su.size()}, {"differences", diff}};
    nlohmann::json je = nlohmann::json::array();
    for (const auto& c : costs) je.push_back({{"name", c.name}, {"bytes", c.bytes}, {"basis", c.basis}});
    j["external_costs"] = je;
    tools::write_json_file(stack_opt.json, j);  // docs/faults.md
  }
  if (!checks_ok) {
    std::fprintf(stderr, "sdins audit stack: the instrument self-check failed: the numbers above cannot be trusted\n");
    return 1;
  }
  if (!all_ok) {
    std::fprintf(stderr, "sdins audit stack: tasks over budget or unbounded (exit status 3)\n");
    return 3;
  }
  return 0;
}

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> v;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) v.push_back(item);
  return v;
}

int run_audit_timing() {
  const sim::Scenario sc = timing_opt.scenario.load();
  tools::TimingAuditConfig cfg;
  cfg.layouts = split_list(timing_opt.layouts);
  if (cfg.layouts.empty()) throw std::runtime_error("--layouts: no layout given");
  if (timing_opt.init == "track")
    cfg.init_mode = fsw::InitMode::kTrack;
  else if (timing_opt.init == "given")
    cfg.init_mode = fsw::InitMode::kGiven;
  else
    throw std::runtime_error("--init: '" + timing_opt.init + "' is neither track nor given");
  // Bus decode (HAL issue): register the decoder as cfg.frame_stages here (tools/timing_audit.hpp).
  const tools::TimingAuditResult r = tools::run_timing_audit(sc, cfg);

  std::printf("timing audit: scenario '%s', %.0f s flight, %ld minor frames per layout, timer overhead %.1f ns "
              "(subtracted)\n\n",
              r.scenario.c_str(), r.flight_s, r.frames, r.timer_overhead_ns);
  std::printf("%-24s %8s %9s %9s %9s %9s %9s %9s %10s %9s\n", "task [us]", "n", "min", "median", "p99", "p99.9", "max",
              "jitter", "cpu share", "preempted");
  for (const auto& t : r.tasks)
    std::printf("%-24s %8ld %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %9.4f%% %9ld\n", t.name.c_str(), t.stats.n,
                t.stats.min_us, t.stats.median_us, t.stats.p99_us, t.stats.p999_us, t.stats.max_us,
                t.release_jitter_max_us, 100.0 * t.cpu_share, t.preempted);
  std::printf("\n%-14s %12s %12s %14s %10s\n", "layout", "fsw share", "EKF updates", "sats min/med/max", "wall [s]");
  for (const auto& l : r.layouts)
    std::printf("%-14s %11.4f%% %12ld %8d/%d/%d %10.2f\n", l.layout.c_str(), 100.0 * l.fsw_cpu_share, l.ekf_updates,
                l.sats_min, l.sats_median, l.sats_max, l.wall_s);
  std::printf("\nStatistics leave out the samples during which the thread was switched out (preempted); jitter is the "
              "start delay on one core at real time with these execution times (SIL releases are exact in virtual "
              "time); see docs/audits.md.\n");
  for (const auto& l : r.layouts)
    std::printf("worst frame %-14s %9.2f us at t=%.3f s (frame %ld): %s\n", l.layout.c_str(), l.worst_frame_us,
                l.worst_frame_t_s, l.worst_frame_index, l.worst_frame_work.c_str());
  for (const auto& l : r.layouts)
    if (l.init_frame >= 0)
      std::printf("initialisation %-11s %9.2f us%s (frame %ld)\n", l.layout.c_str(), l.init_frame_us,
                  l.init_frame_preempted ? " (preempted)" : "", l.init_frame);
  std::printf("\n%-24s %9s %9s %9s %9s %9s %6s\n", "group [us]", "rate [Hz]", "median", "p99", "p99.9", "max", "slips");
  for (const auto& t : r.tasks)
    if (!t.layout.empty())
      std::printf("%-24s %9.1f %9.2f %9.2f %9.2f %9.2f %6ld\n", t.name.c_str(), t.nominal_rate_hz, t.stats.median_us,
                  t.stats.p99_us, t.stats.p999_us, t.stats.max_us, t.slips);

  if (!timing_opt.json.empty()) {
    nlohmann::json j;
    j["tool"] = "sdins audit timing";
    j["scenario"] = r.scenario;
    j["flight_s"] = r.flight_s;
    j["frames"] = r.frames;
    j["timer_overhead_ns"] = r.timer_overhead_ns;
    j["jitter_model"] =
        "SIL ticks are released at their exact virtual times (IMU time tags on the 5 ms grid): virtual-time release "
        "jitter is zero by construction. release_jitter_*_us is the start delay each tick would see on one core at "
        "real time with the measured execution times (start_k = max(k T, finish_k-1)); interrupts and other load are "
        "not modelled.";
    nlohmann::json jt = nlohmann::json::array();
    for (const auto& t : r.tasks) {
      nlohmann::json e{{"name", t.name},
                       {"description", t.description},
                       {"nominal_rate_hz", t.nominal_rate_hz},
                       {"n", t.stats.n},
                       {"min_us", t.stats.min_us},
                       {"median_us", t.stats.median_us},
                       {"p99_us", t.stats.p99_us},
                       {"p999_us", t.stats.p999_us},
                       {"max_us", t.stats.max_us},
                       {"mean_us", t.stats.mean_us},
                       {"cpu_share", t.cpu_share},
                       {"release_jitter_max_us", t.release_jitter_max_us},
                       {"release_jitter_p99_us", t.release_jitter_p99_us},
                       {"deadline_misses", t.deadline_misses},
                       {"preempted", t.preempted},
                       {"max_including_preempted_us", t.max_including_preempted_us}};
      if (!t.layout.empty()) e["layout"] = t.layout;
      if (t.interval_frames_max > 0) e["interval_frames"] = {{"min", t.interval_frames_min}, {"max", t.interval_frames_max}};
      jt.push_back(e);
    }
    j["tasks"] = jt;
    // The rate groups (issue 16): one entry per group and layout.
    nlohmann::json jg = nlohmann::json::array();
    for (const auto& t : r.tasks) {
      if (t.layout.empty()) continue;
      nlohmann::json g{{"name", t.name},
                       {"layout", t.layout},
                       {"rate_hz", t.nominal_rate_hz},
                       {"n", t.stats.n},
                       {"median_us", t.stats.median_us},
                       {"p99_us", t.stats.p99_us},
                       {"p999_us", t.stats.p999_us},
                       {"max_us", t.stats.max_us},
                       {"slips", t.slips}};
      if (t.response_max_us > 0) g["response_max_us"] = t.response_max_us;
      jg.push_back(g);
    }
    j["groups"] = jg;
    j["init_mode"] = timing_opt.init;
    nlohmann::json jl = nlohmann::json::array();
    for (const auto& l : r.layouts)
      jl.push_back({{"layout", l.layout},
                    {"fsw_cpu_share", l.fsw_cpu_share},
                    {"ekf_updates", l.ekf_updates},
                    {"fsw_errors", l.fsw_errors},
                    {"satellites", {{"min", l.sats_min}, {"median", l.sats_median}, {"max", l.sats_max}}},
                    {"wall_s", l.wall_s},
                    {"initialisation_frame", {{"index", l.init_frame},
                                              {"us", l.init_frame_us},
                                              {"preempted", l.init_frame_preempted}}},
                    {"ekf_slips_counted", l.ekf_slips_counted},
                    {"ekf_late_counted", l.ekf_late_counted},
                    {"worst_frame", {{"us", l.worst_frame_us},
                                     {"index", l.worst_frame_index},
                                     {"t_s", l.worst_frame_t_s},
                                     {"work", l.worst_frame_work}}}});
    j["layouts"] = jl;
    tools::write_json_file(timing_opt.json, j);  // docs/faults.md
  }
  return 0;
}

/// sdins audit target: the script does the work (it builds the arm-cortex-m7 preset, runs QEMU with a
/// time limit, the host replay and the comparison); this front end finds the programs it needs.
int run_audit_target() {
  namespace fs = std::filesystem;
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const fs::path tool = exe.parent_path() / "target" / "sdins_target";
  if (!fs::exists(tool))
    throw std::runtime_error("sdins_target not found beside sdins (" + tool.string() +
                             "): audit target runs from a build tree (cmake --build --preset release)");
  const std::string src = project_source_dir(target_opt.source_dir);  // the image is built from the sources
  const std::string dir = target_opt.out_dir.empty() ? src + "/build/target-audit" : target_opt.out_dir;
  std::string cmd;
  if (!target_opt.json.empty()) cmd = "SDINS_TARGET_JSON=" + shell_quote(fs::absolute(target_opt.json).string()) + " ";
  cmd += shell_quote(src + "/tests/e2e/target_qemu.sh") + " " + shell_quote(src) +
         " " + shell_quote(exe.string()) + " " + shell_quote(tool.string()) + " " + shell_quote(dir) + " " +
         std::to_string(target_opt.duration_s);
  const int rc = std::system(cmd.c_str());
  return rc == 0 ? 0 : 1;
}

}  // namespace

void register_audit(CLI::App& app) {
  CLI::App* audit = app.add_subcommand("audit", "Flight-software audits: worst-case stack (stack), execution time (timing), the Cortex-M7 "
                                      "image in QEMU against the host (target).");
  audit->require_subcommand(1);
  g_stack = audit->add_subcommand(
      "stack",
      "Builds fsw/ with GCC -fstack-usage -fcallgraph-info=su (preset stack-audit), computes the worst-case stack of "
      "each task (200 Hz mechanization and 1 Hz EKF per layout) over the call graph, flags recursion, indirect calls, "
      "dynamic frames and heap calls as unbounded, and reports the static RAM of the fsw library. Exit status 3 when "
      "a task is over budget or unbounded.");
  g_stack->add_option("--json", stack_opt.json, "write the report as JSON");
  g_stack->add_option("--budget", stack_opt.budget_bytes, "stack budget per task [bytes]")->capture_default_str()->check(CLI::Range(1L, 1L << 30));
  g_stack->add_option("--build-dir", stack_opt.build_dir, "stack-audit build directory (default: <source>/build/stack-audit)");
  g_stack->add_option("--source-dir", stack_opt.source_dir,
                      "the project's source tree to build (default: the current directory or a parent of it when it "
                      "is the source tree, else the source of the build tree sdins runs from)");
  g_stack->add_flag("--no-build", stack_opt.no_build, "analyse the build directory as it is (no configure/build)");
  g_stack->add_option("--jobs", stack_opt.jobs, "parallel compile jobs")->capture_default_str()->check(CLI::Range(1, 64));
  g_timing = audit->add_subcommand(
      "timing",
      "Flies a scenario through the fsw executive of each layout (SIL: truth -> IMU/GPS models -> Executive::tick) "
      "and reports per task execution time min/median/p99/p99.9/max, release jitter and the share of one core at "
      "real time.");
  add_scenario_options(g_timing, timing_opt.scenario);
  g_timing->add_option("--layouts", timing_opt.layouts, "comma-separated: Layout15, Layout24, Layout15Full, Layout24Full")
      ->capture_default_str();
  g_timing->add_option("--init", timing_opt.init,
                       "track: initialise in flight from the GNSS as HIL does (timed); given: start from the Monte "
                       "Carlo's given state")
      ->capture_default_str();
  g_timing->add_option("--json", timing_opt.json, "write the report as JSON");
  g_target = audit->add_subcommand(
      "target",
      "Builds the Cortex-M7 image for QEMU's mps2-an500 (preset arm-cortex-m7), runs FlightApp on a recorded "
      "simulated flight under qemu-system-arm -icount with a time limit, compares its navigation output with the "
      "host replay of the same input (matches_host, max_abs_diff per field) and reports instruction counts of the "
      "worst 200 Hz frame and 1 Hz epoch against an estimated budget (docs/baremetal-qemu.md). Exit status 1 on a "
      "mismatch, an overrun or a failure.");
  g_target->add_option("--json", target_opt.json, "write the report as JSON (default: OUT_DIR/target.json)");
  g_target->add_option("--out-dir", target_opt.out_dir, "work directory (default: <source>/build/target-audit)");
  g_target->add_option("--source-dir", target_opt.source_dir,
                       "the project's source tree the image is built from (default: as for audit stack)");
  g_target->add_option("--duration", target_opt.duration_s, "simulated flight [s]")->check(CLI::Range(5.0, 600.0))
      ->capture_default_str();
}

int run_audit() {
  if (g_stack != nullptr && g_stack->parsed()) return run_audit_stack();
  if (g_timing != nullptr && g_timing->parsed()) return run_audit_timing();
  if (g_target != nullptr && g_target->parsed()) return run_audit_target();
  return 1;
}

}  // namespace sdins
