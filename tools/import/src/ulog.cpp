// The PX4 ULog reader (tools/ulog.hpp). Written from the format's specification (PX4 user guide,
// "ULog File Format"); the framing checks and the resynchronisation are this project's own.
#include "tools/ulog.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include "hal/input_file.hpp"

namespace tools::ulog {
namespace {

std::uint16_t u16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
std::uint64_t u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

/// The smallest payload each message type can have (0: not a known type).
std::size_t min_payload(std::uint8_t type, std::uint16_t size, bool& exact) {
  exact = false;
  switch (type) {
    case 'B': return 40;
    case 'F': return 3;   // "a:" at least
    case 'I': return 2;   // key length + one key byte
    case 'M': return 3;
    case 'P': return 2;
    case 'Q': return 3;
    case 'A': return 4;   // multi_id, msg_id, one name byte
    case 'R': exact = true; return 2;
    case 'D': return 2;
    case 'L': return 9;   // level, timestamp
    case 'C': return 11;  // level, tag, timestamp
    case 'S': exact = true; return 8;
    case 'O': exact = true; return 2;
    default: (void)size; return 0;
  }
}

bool plausible_header(const std::uint8_t* p) {
  const std::uint16_t size = u16(p);
  bool exact = false;
  const std::size_t min = min_payload(p[2], size, exact);
  if (min == 0) return false;
  return exact ? size == min : size >= min;
}

bool printable(std::string_view s) {
  for (char c : s)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) return false;
  return true;
}

bool identifier(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

/// "float[3]" -> ("float", 3, true); "uint8_t" -> ("uint8_t", 1, false). False when malformed.
bool split_type(std::string_view t, std::string& base, std::uint32_t& count, bool& is_array) {
  const std::size_t br = t.find('[');
  if (br == std::string_view::npos) {
    base = std::string(t);
    count = 1;
    is_array = false;
    return identifier(base);
  }
  if (t.back() != ']' || br + 2 > t.size() - 1) return false;
  base = std::string(t.substr(0, br));
  const std::string_view digits = t.substr(br + 1, t.size() - br - 2);
  if (digits.empty() || digits.size() > 6) return false;
  std::uint32_t n = 0;
  for (char c : digits) {
    if (c < '0' || c > '9') return false;
    n = n * 10 + static_cast<std::uint32_t>(c - '0');
  }
  if (n > 65535) return false;  // 0 occurs: an empty continuation of a multi-part info ("char[0] key")
  count = n;
  is_array = true;
  return identifier(base);
}

/// "type name" (the key of an I/M/P/Q message and each field of a format).
bool split_key(std::string_view s, std::string& type, std::string& name) {
  const std::size_t sp = s.find(' ');
  if (sp == std::string_view::npos || sp == 0 || sp + 1 >= s.size()) return false;
  type = std::string(s.substr(0, sp));
  name = std::string(s.substr(sp + 1));
  return printable(type) && printable(name) && name.find(' ') == std::string::npos;
}

bool parse_format(std::string_view text, Format& out) {
  const std::size_t colon = text.find(':');
  if (colon == std::string_view::npos || colon == 0) return false;
  out = Format{};
  out.name = std::string(text.substr(0, colon));
  if (!identifier(out.name)) return false;
  std::string_view rest = text.substr(colon + 1);
  std::set<std::string> names;
  while (!rest.empty()) {
    const std::size_t semi = rest.find(';');
    const std::string_view item = rest.substr(0, semi);
    rest = semi == std::string_view::npos ? std::string_view{} : rest.substr(semi + 1);
    if (item.empty()) continue;
    std::string type, name;
    if (!split_key(item, type, name) || !identifier(name) || !names.insert(name).second) return false;
    Field f;
    f.name = name;
    if (!split_type(type, f.type_name, f.count, f.is_array)) return false;
    if (!parse_base_type(f.type_name, f.type)) f.type = BaseType::kNested;
    out.fields.push_back(std::move(f));
  }
  return !out.fields.empty();
}

bool info_value_fits(const std::string& type, std::size_t value_bytes) {
  std::string base;
  std::uint32_t count = 1;
  bool is_array = false;
  BaseType t;
  if (!split_type(type, base, count, is_array) || !parse_base_type(base, t)) return false;
  if (t == BaseType::kChar) return value_bytes <= count;  // a string may be shorter than declared
  return value_bytes == base_size(t) * count;
}

class Parser {
 public:
  Parser(File& f, const Limits& lim) : f_(f), lim_(lim) {}

  void run() {
    const std::uint64_t end = f_.bytes.size();
    std::uint64_t pos = kHeaderBytes;
    if (end >= pos + kMessageHeaderBytes && f_.bytes[pos + 2] == 'B') read_flag_bits(pos);
    // Segments: the file, split at the appended-data offsets (a message may be cut at each).
    std::vector<std::uint64_t> cuts;
    if (f_.has_flag_bits && (f_.incompat_flags[0] & kIncompatDataAppended) != 0) {
      for (std::uint64_t off : f_.appended_offsets) {
        if (off == 0) continue;
        if (off <= kHeaderBytes || off >= end || (!cuts.empty() && off <= cuts.back())) {
          f_.damage.add(Damage::kBadInfo, kHeaderBytes);  // an appended offset outside the file
          continue;
        }
        cuts.push_back(off);
      }
    }
    cuts.push_back(end);
    for (std::uint64_t seg_end : cuts) {
      parse_segment(pos, seg_end);
      pos = seg_end;
    }
    finish();
  }

 private:
  const std::uint8_t* at(std::uint64_t p) const { return f_.bytes.data() + p; }

  /// A plausible message starts at p and ends within end, and `depth` more follow it (or the
  /// segment ends at one of them).
  bool chain_ok(std::uint64_t p, std::uint64_t end, int depth) const {
    for (int k = 0; k <= depth; ++k) {
      if (p == end) return true;
      if (p + kMessageHeaderBytes > end) return k > 0;  // a cut message after good ones
      if (!plausible_header(at(p))) return false;
      const std::uint64_t next = p + kMessageHeaderBytes + u16(at(p));
      if (next > end) return k > 0;
      p = next;
    }
    return true;
  }

  /// The next position after `from` where a chain of three plausible messages starts; end if none.
  std::uint64_t resync(std::uint64_t from, std::uint64_t end) const {
    for (std::uint64_t p = from; p + kMessageHeaderBytes <= end; ++p)
      if (plausible_header(at(p)) && p + kMessageHeaderBytes + u16(at(p)) <= end && chain_ok(p, end, 2)) return p;
    return end;
  }

  void skip(Damage why, std::uint64_t pos, std::uint64_t to) {
    f_.damage.add(why, pos);
    f_.damage.bytes_skipped += to - pos;
  }

  void parse_segment(std::uint64_t pos, std::uint64_t end) {
    while (pos < end) {
      if (end - pos < kMessageHeaderBytes) {
        skip(Damage::kTruncated, pos, end);
        return;
      }
      const std::uint16_t size = u16(at(pos));
      const std::uint64_t next = pos + kMessageHeaderBytes + size;
      const bool fits = next <= end;
      // The next message must at least start like one (a cut header or a message running past
      // the end is the next one's damage, not this one's).
      const bool followed = next >= end || next + kMessageHeaderBytes > end || plausible_header(at(next));
      if (!plausible_header(at(pos)) || !fits || !followed) {
        const std::uint64_t r = resync(pos + 1, end);
        // A plausible last message that runs past the end of the file: the log was cut off.
        const bool cut = r == end && plausible_header(at(pos)) && !fits;
        skip(cut ? Damage::kTruncated : Damage::kBadFraming, pos, r);
        pos = r;
        continue;
      }
      handle(at(pos)[2], pos, pos + kMessageHeaderBytes, size);
      pos = next;
    }
  }

  void read_flag_bits(std::uint64_t pos) {
    const std::uint16_t size = u16(at(pos));
    if (size < 40 || pos + kMessageHeaderBytes + size > f_.bytes.size()) return;  // framing will count it
    const std::uint8_t* p = at(pos + kMessageHeaderBytes);
    std::memcpy(f_.compat_flags.data(), p, 8);
    std::memcpy(f_.incompat_flags.data(), p + 8, 8);
    for (int i = 0; i < 3; ++i) f_.appended_offsets[static_cast<std::size_t>(i)] = u64(p + 16 + 8 * i);
    f_.has_flag_bits = true;
    // The specification: a reader must refuse a file with incompatible flags it does not know.
    for (std::size_t i = 0; i < 8; ++i) {
      const std::uint8_t known = i == 0 ? kIncompatDataAppended : 0;
      if ((f_.incompat_flags[i] & ~known) != 0)
        throw std::runtime_error("ULog sets incompatible flag bits this reader does not know (incompat_flags[" +
                                 std::to_string(i) + "] = " + std::to_string(f_.incompat_flags[i]) +
                                 "): the specification forbids parsing it");
    }
  }

  void handle(std::uint8_t type, std::uint64_t msg_pos, std::uint64_t p, std::uint16_t size) {
    const std::uint8_t* b = at(p);
    switch (type) {
      case 'B':
        if (msg_pos != kHeaderBytes) {
          f_.damage.add(Damage::kBadInfo, msg_pos);  // flag bits must be the first message
          return;
        }
        break;
      case 'F': {
        Format fm;
        if (!parse_format(std::string_view(reinterpret_cast<const char*>(b), size), fm)) {
          f_.damage.add(Damage::kBadFormat, msg_pos);
          return;
        }
        if (!f_.formats.emplace(fm.name, std::move(fm)).second) {
          f_.damage.add(Damage::kBadFormat, msg_pos);  // a second format of the same name: the first stays
          return;
        }
        break;
      }
      case 'I': {
        InfoValue v;
        if (!key_value(b, size, 0, v)) return bad_info(msg_pos);
        if (f_.info.size() >= lim_.max_info_entries) return f_.damage.add(Damage::kLimit, msg_pos);
        f_.info.push_back(std::move(v));
        break;
      }
      case 'M': {
        InfoValue v;
        if (!key_value(b, size, 1, v)) return bad_info(msg_pos);
        auto& parts = f_.multi_info[v.key];  // the parts' types differ (char[n] of each part's length)
        if (b[0] != 0 && !parts.empty()) {
          if (parts.back().size() + v.value.size() > (std::size_t{1} << 24)) return f_.damage.add(Damage::kLimit, msg_pos);
          parts.back().insert(parts.back().end(), v.value.begin(), v.value.end());
        } else {
          if (parts.size() >= lim_.max_info_entries) return f_.damage.add(Damage::kLimit, msg_pos);
          parts.push_back(std::move(v.value));
        }
        break;
      }
      case 'P':
      case 'Q': {
        InfoValue v;
        if (!key_value(b, size, type == 'Q' ? 1 : 0, v) || (v.type != "int32_t" && v.type != "float") ||
            v.value.size() != 4)
          return bad_info(msg_pos);
        if (type == 'Q') {
          f_.default_parameters[v.key] = v.number();
        } else if (!data_section_) {
          f_.parameters[v.key] = v.number();
        } else {
          ++f_.parameter_changes;
        }
        break;
      }
      case 'A': {
        data_section_ = true;
        Subscription s;
        s.multi_id = b[0];
        s.msg_id = u16(b + 1);
        s.name.assign(reinterpret_cast<const char*>(b + 3), size - 3u);
        if (!identifier(s.name) || active_.count(s.msg_id) != 0) {
          f_.damage.add(Damage::kBadSubscription, msg_pos);
          return;
        }
        active_[s.msg_id] = f_.subscriptions.size();
        f_.subscriptions.push_back(std::move(s));
        break;
      }
      case 'R':
        active_.erase(u16(b));
        break;
      case 'D': {
        data_section_ = true;
        const auto it = active_.find(u16(b));
        if (it == active_.end()) {
          f_.damage.add(Damage::kUnknownMsgId, msg_pos);
          return;
        }
        f_.subscriptions[it->second].data.push_back({p + 2, static_cast<std::uint16_t>(size - 2u)});
        break;
      }
      case 'L':
      case 'C': {
        data_section_ = true;
        if (f_.texts.size() >= lim_.max_log_texts) return f_.damage.add(Damage::kLimit, msg_pos);
        LogText t;
        t.level = b[0];
        std::size_t off = 1;
        if (type == 'C') {
          t.tag = u16(b + 1);
          off = 3;
        }
        t.timestamp_us = u64(b + off);
        off += 8;
        t.text.assign(reinterpret_cast<const char*>(b + off), size - off);
        for (char& c : t.text)
          if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) c = '?';
        f_.texts.push_back(std::move(t));
        break;
      }
      case 'S':
        if (!std::equal(kSyncMagic.begin(), kSyncMagic.end(), b)) {
          f_.damage.add(Damage::kBadSync, msg_pos);
          return;
        }
        ++f_.sync_messages;
        break;
      case 'O':
        f_.dropouts.push_back({msg_pos, u16(b)});
        f_.dropout_ms += u16(b);
        break;
      default:
        return;  // not reached: plausible_header() knows only the types above
    }
    ++f_.messages;
  }

  void bad_info(std::uint64_t pos) { f_.damage.add(Damage::kBadInfo, pos); }

  /// I (lead 0), M and Q (lead 1): [lead byte] key_len key value.
  static bool key_value(const std::uint8_t* b, std::uint16_t size, std::size_t lead, InfoValue& v) {
    if (size < lead + 1) return false;
    const std::size_t klen = b[lead];
    if (klen == 0 || lead + 1 + klen > size) return false;
    if (!split_key(std::string_view(reinterpret_cast<const char*>(b + lead + 1), klen), v.type, v.key)) return false;
    v.value.assign(b + lead + 1 + klen, b + size);
    return info_value_fits(v.type, v.value.size());
  }

  /// Size of format `name` with its nested formats; false when a nested type is missing, the
  /// nesting is deeper than the limit, or recursive.
  bool resolve(Format& fm, int depth) {
    if (fm.resolved) return true;
    if (depth > lim_.max_nesting || !visiting_.insert(fm.name).second) return false;
    std::size_t off = 0, last_real_end = 0;
    bool ok = true;
    for (Field& fl : fm.fields) {
      std::size_t esize = base_size(fl.type);
      if (fl.type == BaseType::kNested) {
        const auto it = f_.formats.find(fl.type_name);
        if (it == f_.formats.end() || !resolve(it->second, depth + 1)) {
          ok = false;
          break;
        }
        esize = it->second.size;
      }
      fl.offset = off;
      fl.size = esize * fl.count;
      off += fl.size;
      if (!fl.is_padding()) last_real_end = off;
    }
    visiting_.erase(fm.name);
    if (!ok || off > 65535) return false;
    fm.size = off;
    fm.min_size = last_real_end;
    fm.resolved = true;
    return true;
  }

  void finish() {
    for (auto& [name, fm] : f_.formats) {
      visiting_.clear();
      (void)resolve(fm, 0);
    }
    for (auto& [name, fm] : f_.formats)
      if (!fm.resolved) f_.damage.add(Damage::kUnresolvedFormat, 0);
    for (Subscription& s : f_.subscriptions) {
      const auto it = f_.formats.find(s.name);
      if (it == f_.formats.end() || !it->second.resolved) {
        for (const DataRef& d : s.data) f_.damage.add(Damage::kUnknownMsgId, d.offset - 5);
        s.data.clear();
        continue;
      }
      s.format = &it->second;
      std::vector<DataRef> kept;
      kept.reserve(s.data.size());
      for (const DataRef& d : s.data) {
        if (d.size < s.format->min_size || d.size > s.format->size)
          f_.damage.add(Damage::kDataSize, d.offset - 5);
        else
          kept.push_back(d);
      }
      s.data.swap(kept);
      f_.data_messages += s.data.size();
    }
  }

  File& f_;
  const Limits& lim_;
  bool data_section_ = false;
  std::map<std::uint16_t, std::size_t> active_;  ///< msg_id -> subscription index
  std::set<std::string> visiting_;
};

}  // namespace

std::size_t base_size(BaseType t) {
  switch (t) {
    case BaseType::kInt8: case BaseType::kUInt8: case BaseType::kBool: case BaseType::kChar: return 1;
    case BaseType::kInt16: case BaseType::kUInt16: return 2;
    case BaseType::kInt32: case BaseType::kUInt32: case BaseType::kFloat: return 4;
    case BaseType::kInt64: case BaseType::kUInt64: case BaseType::kDouble: return 8;
    case BaseType::kNested: return 0;
  }
  return 0;
}

bool parse_base_type(std::string_view n, BaseType& out) {
  static const std::pair<const char*, BaseType> kTypes[] = {
      {"int8_t", BaseType::kInt8},   {"uint8_t", BaseType::kUInt8},   {"int16_t", BaseType::kInt16},
      {"uint16_t", BaseType::kUInt16}, {"int32_t", BaseType::kInt32}, {"uint32_t", BaseType::kUInt32},
      {"int64_t", BaseType::kInt64}, {"uint64_t", BaseType::kUInt64}, {"float", BaseType::kFloat},
      {"double", BaseType::kDouble}, {"bool", BaseType::kBool},       {"char", BaseType::kChar}};
  for (const auto& [name, t] : kTypes)
    if (n == name) {
      out = t;
      return true;
    }
  return false;
}

const char* to_string(Damage d) {
  switch (d) {
    case Damage::kTruncated: return "truncated_message";
    case Damage::kBadFraming: return "bad_framing";
    case Damage::kBadFormat: return "bad_format";
    case Damage::kUnresolvedFormat: return "unresolved_format";
    case Damage::kBadInfo: return "bad_info";
    case Damage::kBadSubscription: return "bad_subscription";
    case Damage::kUnknownMsgId: return "unknown_msg_id";
    case Damage::kDataSize: return "data_size";
    case Damage::kBadSync: return "bad_sync";
    case Damage::kLimit: return "limit";
    case Damage::kCount: break;
  }
  return "?";
}

std::uint64_t DamageStats::total() const {
  std::uint64_t n = 0;
  for (std::uint64_t c : counts) n += c;
  return n;
}

void DamageStats::add(Damage d, std::uint64_t offset) {
  ++counts[static_cast<int>(d)];
  if (examples.size() < kMaxExamples) examples.push_back({offset, d});
}

const Field* Format::field(std::string_view n) const {
  for (const Field& f : fields)
    if (f.name == n) return &f;
  return nullptr;
}

std::string InfoValue::text() const {
  if (type.rfind("char", 0) != 0) return {};
  std::string s(value.begin(), value.end());
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) c = '?';
  return s;
}

namespace {
double decode_number(BaseType t, const std::uint8_t* p) {
  switch (t) {
    case BaseType::kInt8: return static_cast<std::int8_t>(p[0]);
    case BaseType::kUInt8: case BaseType::kBool: return p[0];
    case BaseType::kInt16: return static_cast<std::int16_t>(u16(p));
    case BaseType::kUInt16: return u16(p);
    case BaseType::kInt32: {
      const std::uint32_t v = static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
                              (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
      return static_cast<std::int32_t>(v);
    }
    case BaseType::kUInt32:
      return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
             (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
    case BaseType::kInt64: return static_cast<double>(static_cast<std::int64_t>(u64(p)));
    case BaseType::kUInt64: return static_cast<double>(u64(p));
    case BaseType::kFloat: {
      float v;
      std::memcpy(&v, p, 4);  // the host is little-endian like the format (x86-64, AArch64)
      return v;
    }
    case BaseType::kDouble: {
      double v;
      std::memcpy(&v, p, 8);
      return v;
    }
    case BaseType::kChar: case BaseType::kNested: break;
  }
  return std::numeric_limits<double>::quiet_NaN();
}
}  // namespace

double InfoValue::number() const {
  std::string base;
  std::uint32_t count = 1;
  bool is_array = false;
  BaseType t;
  if (!split_type(type, base, count, is_array) || !parse_base_type(base, t) || t == BaseType::kChar ||
      value.size() < base_size(t))
    return std::numeric_limits<double>::quiet_NaN();
  return decode_number(t, value.data());
}

const InfoValue* File::find_info(std::string_view key) const {
  for (const InfoValue& v : info)
    if (v.key == key) return &v;
  return nullptr;
}

std::string File::info_text(std::string_view key) const {
  const InfoValue* v = find_info(key);
  return v == nullptr ? std::string() : v->text();
}

const Subscription* File::find(std::string_view name, int multi_id) const {
  for (const Subscription& s : subscriptions)
    if (s.name == name && s.multi_id == multi_id && s.format != nullptr) return &s;
  return nullptr;
}

double value(const File& file, const DataRef& d, const Field& f, std::uint32_t index) {
  const std::size_t es = base_size(f.type);
  if (es == 0 || f.type == BaseType::kChar || index >= f.count || f.offset + (index + 1) * es > d.size)
    return std::numeric_limits<double>::quiet_NaN();
  return decode_number(f.type, file.payload(d) + f.offset + index * es);
}

std::uint64_t value_u64(const File& file, const DataRef& d, const Field& f) {
  const std::size_t es = base_size(f.type);
  if (f.offset + es > d.size) return 0;
  const std::uint8_t* p = file.payload(d) + f.offset;
  switch (f.type) {
    case BaseType::kUInt64: case BaseType::kInt64: return u64(p);
    case BaseType::kUInt32: case BaseType::kInt32: case BaseType::kUInt16: case BaseType::kUInt8:
      return static_cast<std::uint64_t>(decode_number(f.type, p) < 0 ? 0 : decode_number(f.type, p));
    default: return 0;
  }
}

File parse(std::vector<std::uint8_t> bytes, const Limits& limits) {
  if (bytes.size() < kHeaderBytes) throw std::runtime_error("not a ULog file: shorter than its 16-byte header");
  if (!std::equal(kMagic.begin(), kMagic.end(), bytes.begin()))
    throw std::runtime_error("not a ULog file: the first 7 bytes are not the ULog magic (55 4c 6f 67 01 12 35)");
  File f;
  f.bytes = std::move(bytes);
  f.version = f.bytes[7];
  f.start_timestamp_us = u64(f.bytes.data() + 8);
  Parser(f, limits).run();
  return f;
}

File read(const std::string& path, const Limits& limits) {
  // docs/faults.md, bounded readers: a device, FIFO or directory is refused by kind, not read.
  if (const std::string why = hal::check_input_file(path, limits.max_file_bytes); !why.empty())
    throw std::runtime_error(why);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path);
  in.seekg(0, std::ios::end);
  const std::streamoff n = in.tellg();
  if (n < 0) throw std::runtime_error("cannot read " + path);
  in.seekg(0);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(n));
  if (n > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), n)) throw std::runtime_error("cannot read " + path);
  try {
    return parse(std::move(bytes), limits);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

}  // namespace tools::ulog
