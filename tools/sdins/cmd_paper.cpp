// sdins paper: the reference paper's Monte Carlo end to end. For each gyro misalignment level
// (1-sigma 5 and 15 arcsec) the 15- and 24-state filters fly the same N seeded runs of the
// bank-to-turn scenario; writes figures in the style of the paper's figures 16-19, the section-II
// analysis, summary.json (with the acceptance checks) and report.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "commands.hpp"
#include "montecarlo_case.hpp"
#include "tools/interrupt.hpp"
#include "tools/output_file.hpp"

namespace sdins {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Options {
  ScenarioOptions scenario;
  int runs = 100;
  std::vector<double> levels{5.0, 15.0};
  int threads = 0;
  std::string out = "out/paper";
  bool plots = true;
  bool analysis = true;
} opt;

std::string level_dir(double level) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "mis%02.0f", level);
  return buf;
}

json check(const std::string& name, double value, double limit, bool pass, const std::string& detail) {
  return json{{"name", name}, {"value", value}, {"limit", limit}, {"pass", pass}, {"detail", detail}};
}

const json* find_case(const json& cases, double level, const char* model) {
  for (const auto& c : cases)
    if (c["misalignment_arcsec"].get<double>() == level && c["model"] == model) return &c;
  return nullptr;
}

json acceptance(const json& cases, const std::vector<double>& levels) {
  json checks = json::array();
  for (double level : levels) {
    const json* a = find_case(cases, level, "15");
    const json* b = find_case(cases, level, "24");
    if (!a || !b) continue;
    const std::string lv = std::to_string(static_cast<int>(level)) + " arcsec";
    for (const char* ax : {"E", "N"}) {
      const double x = (*a)["final_residual_sigma_deg"][ax], y = (*b)["final_residual_sigma_deg"][ax];
      const double ratio = std::max(x, y) / std::max(1e-300, std::min(x, y));
      checks.push_back(check(std::string(ax) + " residual sigma, 15 vs 24 state, " + lv, ratio, 1.2, ratio <= 1.2,
                             "max/min of the two filters' final 1-sigma"));
    }
    const double u_end = (*b)["final_residual_sigma_deg"]["U"], u_turn = (*b)["u_sigma_after_first_turn_deg"];
    checks.push_back(check("24-state U sigma does not keep growing, " + lv, u_end / u_turn, 1.2, u_end <= 1.2 * u_turn,
                           "final U 1-sigma / U 1-sigma after the first turn"));
    if (level == 15.0) {
      const double u15 = (*a)["final_residual_sigma_deg"]["U"];
      checks.push_back(check("24-state U sigma at most half the 15-state one, " + lv, u_end / u15, 0.5,
                             u_end <= 0.5 * u15, "final U 1-sigma, 24-state / 15-state"));
    }
    // The misalignment combinations the manoeuvres make observable (filter sigma at most half the
    // initial one) must really converge: the RMS residual across runs along each within the 99%
    // chi-square bound of an RMS of `runs` samples with the filter's sigma.
    {
      const int runs = (*b)["runs"];
      const double z = 2.326348, k = runs, a9 = 2.0 / (9.0 * k);
      const double rms_bound = std::sqrt(std::pow(1.0 - a9 + z * std::sqrt(a9), 3.0));
      int n_obs = 0;
      for (const auto& cmb : (*b)["misalignment_combinations"]) {
        if (!cmb["observable"].get<bool>()) continue;
        ++n_obs;
        const double ratio = cmb["rms_residual"].get<double>() / cmb["filter_sigma"].get<double>();
        checks.push_back(check("observable misalignment combination converges, " + cmb["label"].get<std::string>() +
                                   ", " + lv,
                               ratio, rms_bound, ratio <= rms_bound,
                               "RMS residual / filter 1-sigma along the combination (filter sigma " +
                                   std::to_string(cmb["filter_sigma"].get<double>()) + " arcsec of " +
                                   std::to_string(cmb["initial_sigma"].get<double>()) + ")"));
      }
      checks.push_back(check("the manoeuvres make at least one misalignment combination observable, " + lv, n_obs, 1,
                             n_obs >= 1, "combinations whose filter sigma fell to at most half the initial one"));
    }
    for (const json* c : {a, b}) {
      const double nees = (*c)["mean_nees"];
      const double lo = (*c)["nees_bounds"][0], hi = (*c)["nees_bounds"][1];
      // docs/faults.md: a NEES "in bounds" with no pseudorange used says nothing about the aided filter.
      const double pr_used = (*c)["health"]["pr_used"];
      checks.push_back(check("pseudoranges used by the " + (*c)["model"].get<std::string>() + "-state filter, " + lv,
                             pr_used, 1.0, pr_used >= 1.0, "pseudoranges used over all runs (0: no GNSS aiding)"));
      checks.push_back(check("mean NEES of the " + (*c)["model"].get<std::string>() + "-state filter, " + lv, nees, hi,
                             nees >= lo && nees <= hi && pr_used >= 1.0,
                             "time average of the run-averaged 9-dof NEES; 95% bounds [" + std::to_string(lo) + ", " +
                                 std::to_string(hi) + "]"));
    }
  }
  return checks;
}

void write_report(const fs::path& out, const json& summary) {
  tools::TextOutput report((out / "report.md").string());
  std::ostream& f = report.os();
  f << "# Paper reproduction: 15-state versus 24-state tightly coupled SDINS/GPS filter\n\n"
    << "Scenario `" << summary["scenario"].get<std::string>() << "`, " << summary["duration_s"].get<double>()
    << " s of alternating 180-degree bank-to-turn manoeuvres; " << summary["runs"].get<int>()
    << " seeded runs per case; both filters fly the same runs. Residual attitude error = INS attitude error minus the "
       "filter's estimate (paper eq. 12), after each 1 Hz update.\n\n"
    << "| gyro misalignment 1-sigma | model | runs | final residual 1-sigma E / N / U [deg] | U 1-sigma after 1st turn "
       "[deg] | mean NEES | 95% bounds | wall [s] |\n"
    << "|---|---|---|---|---|---|---|---|\n";
  char buf[512];
  for (const auto& c : summary["cases"]) {
    const auto& s = c["final_residual_sigma_deg"];
    std::snprintf(buf, sizeof buf, "| %.0f arcsec | %s | %d | %.5f / %.5f / %.5f | %.5f | %.2f | [%.2f, %.2f] | %.1f |\n",
                  c["misalignment_arcsec"].get<double>(), c["model"].get<std::string>().c_str(), c["runs"].get<int>(),
                  s["E"].get<double>(), s["N"].get<double>(), s["U"].get<double>(),
                  c["u_sigma_after_first_turn_deg"].get<double>(), c["mean_nees"].get<double>(),
                  c["nees_bounds"][0].get<double>(), c["nees_bounds"][1].get<double>(), c["wall_s"].get<double>());
    f << buf;
  }
  f << "\n## Acceptance\n\n| check | value | limit | result |\n|---|---|---|---|\n";
  for (const auto& c : summary["acceptance"]["checks"]) {
    std::snprintf(buf, sizeof buf, "| %s | %.3f | %.3f | %s |\n", c["name"].get<std::string>().c_str(),
                  c["value"].get<double>(), c["limit"].get<double>(), c["pass"].get<bool>() ? "pass" : "**FAIL**");
    f << buf;
  }
  f << "\n## Sensor errors at the end of the flight (24-state filter)\n\n"
    << "RMS across runs of the residual (truth minus the filter's final compensation) against its initial 1-sigma; "
       "`converged` when the RMS residual is at most half the initial 1-sigma.\n\n"
    << "| misalignment level | state | unit | initial 1-sigma | RMS residual | filter 1-sigma | converged |\n"
    << "|---|---|---|---|---|---|---|\n";
  for (const auto& c : summary["cases"]) {
    if (c["model"] != "24") continue;
    for (const auto& x : c["sensors"]) {
      std::snprintf(buf, sizeof buf, "| %.0f arcsec | %s | %s | %.3g | %.3g | %.3g | %s |\n",
                    c["misalignment_arcsec"].get<double>(), x["name"].get<std::string>().c_str(),
                    x["unit"].get<std::string>().c_str(), x["initial_sigma"].get<double>(),
                    x["rms_residual"].get<double>(), x["filter_sigma"].get<double>(),
                    x["converged"].get<bool>() ? "yes" : "no");
      f << buf;
    }
  }
  f << "\n## Which misalignments the manoeuvres make observable (24-state filter)\n\n"
    << "Eigen-directions of the filter's final misalignment covariance (normalised by the initial sigmas), most "
       "reduced first. Single misalignments are not separable in this flight; these combinations are. `observable` "
       "when the filter sigma along the combination is at most half its initial value.\n\n"
    << "| misalignment level | combination | initial 1-sigma [arcsec] | filter 1-sigma | RMS residual | observable |\n"
    << "|---|---|---|---|---|---|\n";
  for (const auto& c : summary["cases"]) {
    if (c["model"] != "24") continue;
    for (const auto& x : c["misalignment_combinations"]) {
      std::snprintf(buf, sizeof buf, "| %.0f arcsec | %s | %.2f | %.2f | %.2f | %s |\n",
                    c["misalignment_arcsec"].get<double>(), x["label"].get<std::string>().c_str(),
                    x["initial_sigma"].get<double>(), x["filter_sigma"].get<double>(), x["rms_residual"].get<double>(),
                    x["observable"].get<bool>() ? "yes" : "no");
      f << buf;
    }
  }
  f << "\n## Figures\n\n";
  for (const auto& e : fs::directory_iterator(out))
    if (e.path().extension() == ".png") f << "- [" << e.path().filename().string() << "](" << e.path().filename().string() << ")\n";
  f << "\nThe section-II analysis (alignment, single-axis rotation, bank-to-turn) is in [analysis/](analysis/summary.md).\n";
  report.commit();
}

int run_paper_body();

}  // namespace

void register_paper(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "paper",
      "Reproduce the reference paper end to end: Monte Carlo of the 15- and 24-state filters at gyro misalignment "
      "1-sigma 5 and 15 arcsec, figures in the style of the paper's figures 16-19, the section-II analysis, "
      "summary.json with the acceptance checks and report.md.");
  add_scenario_options(sub, opt.scenario);
  sub->add_option("--runs", opt.runs, "runs per case")->check(CLI::Range(2, 100000))->capture_default_str();
  sub->add_option("--levels", opt.levels, "gyro misalignment 1-sigma levels [arcsec]")->delimiter(',')->capture_default_str();
  sub->add_option("--threads", opt.threads, "worker threads (0: all cores)")->check(CLI::Range(0, 1024))->capture_default_str();
  sub->add_option("--out", opt.out, "output directory")->capture_default_str();
  sub->add_flag("!--no-plots", opt.plots, "skip the PNG figures (matplotlib)");
  sub->add_flag("!--no-analysis", opt.analysis, "skip the section-II analysis");
}

int run_paper() { return run_guarded(run_paper_body); }

namespace {
int run_paper_body() {
  const sim::Scenario base = opt.scenario.load();
  const fs::path out(opt.out);
  const bool root_rank = mpi_world().rank == 0;
  tools::require_distinct({opt.out}, {opt.scenario.file});
  std::optional<tools::RunDirectory> run_dir;  // docs/faults.md: summary.json removed now, written last
  if (root_rank) run_dir.emplace(opt.out);
  const tools::InterruptPolling polling;
  json cases = json::array();
  bool root = true;
  double wall_total = 0.0;
  for (double level : opt.levels) {
    if (!(level >= 0.0 && level <= 3600.0)) throw std::runtime_error("--levels: misalignment out of range");
    sim::Scenario sc = base;
    sc.imu.errors = sim::ImuErrorSet::kPaper;
    sc.imu.sigmas.gyro_misalignment_arcsec = level;
    tools::MonteCarloConfig mc;
    mc.runs = opt.runs;
    mc.threads = opt.threads;
    mc.models = {tools::Model::k15, tools::Model::k24};
    const std::string dir = level_dir(level);
    if (root_rank) fs::create_directories(out / dir);
    std::printf("gyro misalignment 1-sigma %.0f arcsec: %d runs, 15- and 24-state filters\n", level, opt.runs);
    std::fflush(stdout);
    const CaseResult r = run_case(sc, mc, (out / dir).string(), "");
    if (!r.written) {
      root = false;
      continue;
    }
    print_case(r);
    wall_total += r.wall_s;
    for (json m : r.models) {
      m["misalignment_arcsec"] = level;
      m["wall_s"] = r.wall_s;
      m["csv"] = dir + "/" + m["csv"].get<std::string>();
      cases.push_back(m);
    }
  }
  if (!root) return 0;
  json summary;
  summary["scenario"] = base.name;
  summary["duration_s"] = base.duration_s;
  summary["runs"] = opt.runs;
  summary["seed"] = base.seed;
  summary["cases"] = cases;
  const json checks = acceptance(cases, opt.levels);
  bool all = true;
  for (const auto& c : checks) all = all && c["pass"].get<bool>();
  summary["acceptance"] = {{"checks", checks}, {"all_pass", all}};
  summary["wall_s"] = wall_total;
  if (opt.analysis) {
    std::printf("section-II analysis -> %s\n", (out / "analysis").string().c_str());
    std::fflush(stdout);
    if (run_analysis(base, (out / "analysis").string(), 20.0, opt.plots) != 0) return 1;
  }
  write_report(out, summary);
  tools::throw_if_interrupted("paper stopped before its summary; no summary.json written");
  run_dir->finish(summary);  // the completion marker; the figures below are drawn from it
  if (opt.plots && run_plot_script("plot_paper.py", "\"" + out.string() + "\"") != 0)
    std::fprintf(stderr, "sdins paper: warning: the figures could not be made (plot_paper.py failed)\n");
  std::printf("\nacceptance:\n");
  for (const auto& c : checks)
    std::printf("  %-4s %-62s %8.3f (limit %.3f)\n", c["pass"].get<bool>() ? "ok" : "FAIL",
                c["name"].get<std::string>().c_str(), c["value"].get<double>(), c["limit"].get<double>());
  std::printf("wrote %s/{summary.json,report.md,mis*/stats_*.csv,*.png,analysis/}\n", out.string().c_str());
  return 0;
}
}  // namespace

}  // namespace sdins
