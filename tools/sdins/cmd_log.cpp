// sdins log info | export: inspect LCM logs (hal/lcm_log.hpp, message types in hal/lcm/*.lcm).
//   info:   channels with message counts, message type (from the LCM fingerprint), time span,
//           and every rejection the reader and the decoders counted.
//   export: one channel to CSV, one row per message, header = field names (which carry units).
#include <cinttypes>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "commands.hpp"
#include "tools/output_file.hpp"
#include "hal/lcm_log.hpp"
#include "hal/lcm_types.hpp"

namespace sdins {
namespace {

struct LogOptions {
  std::string log;
  bool json = false;
  std::size_t show_rejections = 20;
  std::string channel;
  std::string csv;
} log_opt;

CLI::App* info_cmd = nullptr;
CLI::App* export_cmd = nullptr;

std::string hex_fingerprint(std::int64_t fp) {
  char buf[24];
  std::snprintf(buf, sizeof(buf), "0x%016" PRIx64, static_cast<std::uint64_t>(fp));
  return buf;
}

struct ChannelSummary {
  std::string name;
  std::uint64_t messages = 0;
  std::map<std::int64_t, std::uint64_t> by_fingerprint;
  bool have_t = false;
  double t_first_s = 0.0, t_last_s = 0.0;   ///< message t_s (decodable project types)
  std::int64_t ts_first_us = 0, ts_last_us = 0;  ///< event timestamps of the first and last message
  std::uint64_t wrong_type = 0;     ///< fingerprint is not the channel's type
  std::uint64_t decode_failed = 0;  ///< a project type's fingerprint, but the bytes do not decode
  std::uint64_t unknown_type = 0;   ///< fingerprint of no project type (foreign channels)
  /// The flight software's input conversion (the replay reader's): rejections by status, and GNSS
  /// measurements removed from accepted epochs (non-finite pseudorange, rate or C/N0).
  std::map<std::string, std::uint64_t> input_rejected;
  std::uint64_t measurements_dropped = 0;
  std::uint64_t input_rejected_total() const {
    std::uint64_t n = 0;
    for (const auto& [why, k] : input_rejected) n += k;
    return n;
  }

  std::string type_text() const {
    std::string s;
    for (const auto& [fp, n] : by_fingerprint) {
      const hal::LcmTypeInfo* t = hal::find_lcm_type(fp);
      const std::string type = t != nullptr ? t->name : "unknown(" + hex_fingerprint(fp) + ")";
      if (by_fingerprint.size() == 1) return type;
      s += (s.empty() ? "" : ",") + type + ":" + std::to_string(n);
    }
    return s.empty() ? "-" : "mixed[" + s + "]";
  }
};

void open_log(hal::LcmLogReader& r, const std::string& path) {
  if (r.open(path) != hal::LcmLogStatus::kOk) throw std::runtime_error("cannot read log " + r.error());
}

nlohmann::json reader_rejections_json(const hal::LcmLogReadStats& st) {
  nlohmann::json j = nlohmann::json::object();
  for (int r = 0; r < static_cast<int>(hal::LcmLogRejection::kCount); ++r)
    j[hal::to_string(static_cast<hal::LcmLogRejection>(r))] = st.rejections[r];
  return j;
}

void print_reader_rejections(const hal::LcmLogReadStats& st, std::size_t show, std::FILE* out) {
  std::fprintf(out, "reader rejections: %" PRIu64, st.total_rejections());
  const char* sep = " (";
  for (int r = 0; r < static_cast<int>(hal::LcmLogRejection::kCount); ++r) {
    std::fprintf(out, "%s%s %" PRIu64, sep, hal::to_string(static_cast<hal::LcmLogRejection>(r)), st.rejections[r]);
    sep = ", ";
  }
  std::fprintf(out, "), %" PRIu64 " bytes skipped\n", st.bytes_skipped);
  for (std::size_t i = 0; i < st.records.size() && i < show; ++i)
    std::fprintf(out, "  at byte %" PRIu64 ": %s, %" PRIu64 " bytes skipped\n", st.records[i].offset,
                 hal::to_string(st.records[i].reason), st.records[i].bytes);
  if (st.total_rejections() > show && show > 0)
    std::fprintf(out, "  ... %" PRIu64 " more\n", st.total_rejections() - std::min<std::uint64_t>(show, st.records.size()));
}

int run_info() {
  hal::LcmLogReader reader;
  open_log(reader, log_opt.log);
  std::vector<ChannelSummary> channels;
  std::unordered_map<std::string, std::size_t> index;
  bool have_ts = false;
  std::int64_t ts_first = 0, ts_last = 0;
  hal::LcmLogEvent ev;
  while (reader.next(ev) == hal::LcmLogStatus::kOk) {
    auto [it, inserted] = index.try_emplace(std::string(ev.channel), channels.size());
    if (inserted) {
      channels.emplace_back();
      channels.back().name = std::string(ev.channel);
    }
    ChannelSummary& c = channels[it->second];
    if (c.messages == 0) c.ts_first_us = ev.timestamp_us;
    c.ts_last_us = ev.timestamp_us;
    ++c.messages;
    if (!have_ts || ev.timestamp_us < ts_first) ts_first = ev.timestamp_us;
    if (!have_ts || ev.timestamp_us > ts_last) ts_last = ev.timestamp_us;
    have_ts = true;
    const std::int64_t fp = hal::lcm_fingerprint(ev.data, ev.data_len);
    ++c.by_fingerprint[fp];
    const hal::LcmTypeInfo* expected = hal::lcm_channel_type(ev.channel);
    const hal::LcmTypeInfo* type = hal::find_lcm_type(fp);
    if (expected != nullptr && type != expected) {
      ++c.wrong_type;
      continue;
    }
    if (type == nullptr) {
      ++c.unknown_type;
      continue;
    }
    double t_s = 0.0;
    if (type->time(ev.data, ev.data_len, t_s) != hal::LcmInputStatus::kOk) {
      ++c.decode_failed;
      continue;
    }
    if (type->input != nullptr) {
      int dropped = 0;
      const hal::LcmInputStatus in = type->input(ev.data, ev.data_len, dropped);
      c.measurements_dropped += static_cast<std::uint64_t>(dropped);
      if (in != hal::LcmInputStatus::kOk && in != hal::LcmInputStatus::kMeasurementsDropped)
        ++c.input_rejected[hal::to_string(in)];
    }
    if (!c.have_t || t_s < c.t_first_s) c.t_first_s = t_s;
    if (!c.have_t || t_s > c.t_last_s) c.t_last_s = t_s;
    c.have_t = true;
  }
  const hal::LcmLogReadStats& st = reader.stats();
  // docs/faults.md: a log with no valid event is an error (exit 1), after the summary is printed.
  const auto nothing_valid = [&] {
    if (st.events > 0) return 0;
    std::fprintf(stderr, "sdins: error: %s: no valid LCM event in %llu bytes (%llu rejections)\n", log_opt.log.c_str(),
                 static_cast<unsigned long long>(reader.file_size()),
                 static_cast<unsigned long long>(st.total_rejections()));
    return 1;
  };

  if (log_opt.json) {
    nlohmann::json j;
    j["log"] = log_opt.log;
    j["bytes"] = reader.file_size();
    j["events"] = st.events;
    j["event_timestamp_min_us"] = ts_first;
    j["event_timestamp_max_us"] = ts_last;
    j["reader_rejections"] = reader_rejections_json(st);
    j["reader_rejections_total"] = st.total_rejections();
    j["bytes_skipped"] = st.bytes_skipped;
    nlohmann::json recs = nlohmann::json::array();
    for (const auto& r : st.records) recs.push_back({{"offset", r.offset}, {"bytes", r.bytes}, {"reason", hal::to_string(r.reason)}});
    j["rejection_records"] = recs;
    nlohmann::json chans = nlohmann::json::array();
    for (const ChannelSummary& c : channels) {
      nlohmann::json cj{{"channel", c.name},
                        {"messages", c.messages},
                        {"type", c.type_text()},
                        {"wrong_type", c.wrong_type},
                        {"decode_failed", c.decode_failed},
                        {"unknown_type", c.unknown_type},
                        {"input_rejected", c.input_rejected_total()},
                        {"input_rejections", c.input_rejected},
                        {"measurements_dropped", c.measurements_dropped},
                        {"event_timestamp_first_us", c.ts_first_us},
                        {"event_timestamp_last_us", c.ts_last_us}};
      if (c.have_t) {
        cj["t_first_s"] = c.t_first_s;
        cj["t_last_s"] = c.t_last_s;
      }
      chans.push_back(cj);
    }
    j["channels"] = chans;
    std::printf("%s\n", j.dump(2).c_str());
    return nothing_valid();
  }

  std::printf("log %s: %" PRIu64 " bytes, %" PRIu64 " events, %zu channels\n", log_opt.log.c_str(), reader.file_size(),
              st.events, channels.size());
  if (have_ts)
    std::printf("event timestamps: %.6f .. %.6f s (span %.6f s)\n", static_cast<double>(ts_first) * 1e-6,
                static_cast<double>(ts_last) * 1e-6, static_cast<double>(ts_last - ts_first) * 1e-6);
  std::printf("%-16s %10s  %-30s %-28s %s\n", "channel", "messages", "type", "t_s span [s]", "rejected");
  for (const ChannelSummary& c : channels) {
    char span[64] = "-";
    if (c.have_t) std::snprintf(span, sizeof(span), "%.6f .. %.6f", c.t_first_s, c.t_last_s);
    std::string rej = std::to_string(c.wrong_type + c.decode_failed + c.input_rejected_total());
    if (c.wrong_type + c.decode_failed + c.input_rejected_total() > 0) {
      rej += " (wrong_type " + std::to_string(c.wrong_type) + ", decode_failed " + std::to_string(c.decode_failed);
      for (const auto& [why, k] : c.input_rejected) rej += ", " + why + " " + std::to_string(k);
      rej += ")";
    }
    // docs/faults.md: measurements the flight software's input conversion removes are counted here.
    if (c.measurements_dropped > 0)
      rej += "; " + std::to_string(c.measurements_dropped) + " measurements with non-finite values dropped";
    std::printf("%-16s %10" PRIu64 "  %-30s %-28s %s\n", c.name.c_str(), c.messages, c.type_text().c_str(), span,
                rej.c_str());
  }
  print_reader_rejections(st, log_opt.show_rejections, stdout);
  return nothing_valid();
}

int run_export() {
  tools::require_distinct({log_opt.csv}, {log_opt.log});
  hal::LcmLogReader reader;
  open_log(reader, log_opt.log);
  // docs/faults.md: the CSV is written to a temporary file and renamed into place only when complete.
  tools::TextOutput csv_out(log_opt.csv);
  std::ostream& csv = csv_out.os();
  const hal::LcmTypeInfo* expected = hal::lcm_channel_type(log_opt.channel);
  const hal::LcmTypeInfo* type = nullptr;
  std::vector<std::string> header;
  hal::LcmRow row;
  std::uint64_t rows = 0, on_channel = 0, wrong_type = 0, unknown_type = 0, decode_failed = 0;
  hal::LcmLogEvent ev;
  while (reader.next(ev) == hal::LcmLogStatus::kOk) {
    if (ev.channel != log_opt.channel) continue;
    ++on_channel;
    const hal::LcmTypeInfo* t = hal::find_lcm_type(hal::lcm_fingerprint(ev.data, ev.data_len));
    if (t == nullptr) {
      ++unknown_type;
      continue;
    }
    if ((expected != nullptr && t != expected) || (type != nullptr && t != type)) {
      ++wrong_type;
      continue;
    }
    if (t->row(ev.data, ev.data_len, row) != hal::LcmInputStatus::kOk) {
      ++decode_failed;
      continue;
    }
    if (type == nullptr) {
      type = t;
      header = row.names();
      for (std::size_t i = 0; i < header.size(); ++i) csv << (i ? "," : "") << header[i];
      csv << '\n';
    } else if (row.names() != header) {
      throw std::runtime_error("message " + std::to_string(on_channel) + " on " + log_opt.channel +
                               " has a different field layout than the first (e.g. another EKF model); "
                               "a CSV needs one header");
    }
    const auto& cells = row.cells();
    for (std::size_t i = 0; i < cells.size(); ++i) csv << (i ? "," : "") << cells[i];
    csv << '\n';
    ++rows;
  }
  if (rows == 0) {
    print_reader_rejections(reader.stats(), log_opt.show_rejections, stderr);
    throw std::runtime_error("no message of a known type on channel '" + log_opt.channel + "' of " + log_opt.log +
                             " (see sdins log info); no CSV written");
  }
  csv_out.commit();
  std::fprintf(stderr, "%s: %" PRIu64 " rows of %s from channel %s (%" PRIu64
                       " messages on it; skipped: %" PRIu64 " wrong_type, %" PRIu64 " unknown_type, %" PRIu64
                       " decode_failed)\n",
               log_opt.csv.c_str(), rows, type != nullptr ? type->name.c_str() : "-", log_opt.channel.c_str(), on_channel,
               wrong_type, unknown_type, decode_failed);
  print_reader_rejections(reader.stats(), log_opt.show_rejections, stderr);
  return 0;
}

}  // namespace

void register_log(CLI::App& app) {
  CLI::App* sub = app.add_subcommand("log", "Inspect LCM logs (the project's telemetry / measured-data format).");
  sub->require_subcommand(1);
  info_cmd = sub->add_subcommand(
      "info", "List a log's channels with message counts, message type (from the LCM fingerprint), time span, and "
              "the reader's and decoders' rejection counts (truncated or corrupted logs are read past the damage).");
  info_cmd->add_option("log", log_opt.log, "LCM log file")->required();
  info_cmd->add_flag("--json", log_opt.json, "print the summary as JSON");
  info_cmd->add_option("--show-rejections", log_opt.show_rejections, "list at most this many rejections with their offsets")
      ->capture_default_str();
  export_cmd = sub->add_subcommand(
      "export", "Write one channel of a log as CSV: one row per message, a header of field names carrying their units "
                "(arrays as name[i]; array slots beyond a count field are empty cells).");
  export_cmd->add_option("log", log_opt.log, "LCM log file")->required();
  export_cmd->add_option("--channel", log_opt.channel, "channel to export, e.g. NAV_SOLUTION")->required();
  export_cmd->add_option("--csv", log_opt.csv, "output CSV file")->required();
  export_cmd->add_option("--show-rejections", log_opt.show_rejections, "list at most this many reader rejections")
      ->capture_default_str();
}

int run_log() {
  if (info_cmd != nullptr && info_cmd->parsed()) return run_info();
  if (export_cmd != nullptr && export_cmd->parsed()) return run_export();
  return 1;
}

}  // namespace sdins
