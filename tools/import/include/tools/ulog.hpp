// A reader of PX4 ULog files (.ulg), the self-describing binary log of the PX4 autopilot
// (specification: PX4 user guide, "ULog File Format"; docs/ulog.md).
//
// Layout, all little-endian:
//   header (16 bytes): magic "ULog" 01 12 35, version (1 byte), start timestamp [us] (uint64);
//   then messages: uint16 msg_size (payload bytes, header excluded) | uint8 msg_type | payload.
// Definitions section: 'B' flag bits (first, if present), 'F' formats ("name:type field;..."), 'I'
// info, 'M' multi-part info, 'P' parameters, 'Q' default parameters. Data section (from the first
// 'A'): 'A' subscriptions (multi_id, msg_id, topic name), 'R' unsubscriptions, 'D' data (msg_id +
// the topic's fields as the format says, trailing padding fields left out), 'L' / 'C' log text,
// 'S' sync (8 magic bytes), 'O' dropout (ms of data the logger lost), and I/M/P/Q again.
//
// Robustness (docs/faults.md): the reader never reads outside the file and never throws for
// damaged content. A message is taken only when its type is known, its size is plausible for its
// type and it ends where another plausible message header (or the file / an appended segment)
// begins; otherwise the bytes are skipped up to the next position where a chain of three
// plausible messages starts, and the damage is counted with its reason and file offset.
// Content errors (a malformed format, an info key without a type, a data message for an unknown
// msg_id or of the wrong size) are counted and the message skipped. Only a file that is not a
// ULog (short header, wrong magic) or that sets incompatible flag bits this reader does not know
// (the specification says such a file must not be parsed) throws std::runtime_error.
// Memory is bounded by the file: data messages are kept as offsets into the file's bytes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace tools::ulog {

inline constexpr std::size_t kHeaderBytes = 16;
inline constexpr std::size_t kMessageHeaderBytes = 3;
inline constexpr std::array<std::uint8_t, 7> kMagic{0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35};
inline constexpr std::array<std::uint8_t, 8> kSyncMagic{0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12};
/// incompat_flags[0] bit 0: data were appended at appended_offsets (the only incompatible flag
/// the specification defines).
inline constexpr std::uint8_t kIncompatDataAppended = 0x01;

enum class BaseType : std::uint8_t {
  kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kInt64, kUInt64, kFloat, kDouble, kBool, kChar,
  kNested,  ///< another format (a nested message type)
};
/// Bytes of one element (0 for kNested).
std::size_t base_size(BaseType t);
/// "float" -> kFloat; false for a name that is not a base type.
bool parse_base_type(std::string_view name, BaseType& out);

struct Field {
  std::string name;
  std::string type_name;  ///< as written: "float", "uint8_t", or a nested format's name
  BaseType type = BaseType::kUInt8;
  std::uint32_t count = 1;  ///< array length (1 for a scalar)
  bool is_array = false;
  std::size_t offset = 0;   ///< within the topic's data (after the data message's msg_id)
  std::size_t size = 0;     ///< bytes of the whole field (all elements)
  bool is_padding() const { return name.rfind("_padding", 0) == 0; }
};

struct Format {
  std::string name;
  std::vector<Field> fields;
  bool resolved = false;    ///< every nested type found: offsets and sizes are valid
  std::size_t size = 0;     ///< bytes of the whole message
  std::size_t min_size = 0; ///< without the trailing padding fields (which the logger leaves out)
  const Field* field(std::string_view name) const;
};

/// A data message: its payload (the topic's bytes, after the msg_id) in the file's bytes.
struct DataRef {
  std::uint64_t offset = 0;
  std::uint16_t size = 0;
};

struct Subscription {
  std::uint16_t msg_id = 0;
  std::uint8_t multi_id = 0;
  std::string name;             ///< the topic (= its format's name)
  const Format* format = nullptr;  ///< null when the log has no usable format of that name
  std::vector<DataRef> data;    ///< data messages whose size fits the format, in file order
};

/// An 'I' or 'Q'/'P' entry: the key "type name" split, and the raw value bytes.
struct InfoValue {
  std::string type;  ///< e.g. "char[20]", "int32_t"
  std::string key;
  std::vector<std::uint8_t> value;
  /// The value as text (char arrays; non-printable bytes as '?'), empty for other types.
  std::string text() const;
  /// The value as a number (integer and float types; NaN for others or a short value).
  double number() const;
};

struct LogText {
  std::uint8_t level = 0;   ///< as logged: '0'..'7' (ASCII, syslog levels) in PX4's logs
  std::int32_t tag = -1;    ///< 'C' messages: the tag; 'L': -1
  std::uint64_t timestamp_us = 0;
  std::string text;
};

struct Dropout {
  std::uint64_t offset = 0;
  std::uint16_t duration_ms = 0;
};

/// Why bytes or messages of a file were not used.
enum class Damage : std::uint8_t {
  kTruncated = 0,      ///< a message cut short by the end of the file (or of an appended segment)
  kBadFraming,         ///< unknown type, implausible size, or the next message does not follow: bytes skipped
  kBadFormat,          ///< an 'F' message that does not parse
  kUnresolvedFormat,   ///< a format with a nested type that is not defined (or is recursive)
  kBadInfo,            ///< an I/M/P/Q message that does not parse or whose value size fits no type
  kBadSubscription,    ///< an 'A' message without a name, or its msg_id taken
  kUnknownMsgId,       ///< a data message for a msg_id nobody subscribed (or whose format is unusable)
  kDataSize,           ///< a data message whose size does not fit its format
  kBadSync,            ///< an 'S' message without the sync magic
  kLimit,              ///< a bounded table is full (log texts, info entries): counted, not kept
  kCount
};
const char* to_string(Damage d);

struct DamageRecord {
  std::uint64_t offset = 0;
  Damage reason = Damage::kBadFraming;
};

struct DamageStats {
  std::array<std::uint64_t, static_cast<int>(Damage::kCount)> counts{};
  std::uint64_t bytes_skipped = 0;  ///< bytes not part of any accepted message
  std::vector<DamageRecord> examples;  ///< the first kMaxExamples, in file order
  static constexpr std::size_t kMaxExamples = 20;
  std::uint64_t count(Damage d) const { return counts[static_cast<int>(d)]; }
  std::uint64_t total() const;
  void add(Damage d, std::uint64_t offset);
};

struct Limits {
  std::uint64_t max_file_bytes = std::uint64_t{4} << 30;  ///< larger files are refused (read())
  std::size_t max_log_texts = 100000;
  std::size_t max_info_entries = 100000;
  int max_nesting = 16;  ///< depth of nested formats
};

struct File {
  std::vector<std::uint8_t> bytes;  ///< the whole file (data messages point into it)
  std::uint8_t version = 0;
  std::uint64_t start_timestamp_us = 0;
  bool has_flag_bits = false;
  std::array<std::uint8_t, 8> compat_flags{};
  std::array<std::uint8_t, 8> incompat_flags{};
  std::array<std::uint64_t, 3> appended_offsets{};
  std::map<std::string, Format> formats;
  std::vector<InfoValue> info;                                   ///< 'I', in order
  /// 'M': name -> entries, each the joined value bytes of a message and its continuations.
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> multi_info;
  std::map<std::string, double> parameters;   ///< 'P' of the definitions section (int32 and float)
  std::uint64_t parameter_changes = 0;        ///< 'P' in the data section (changes in flight)
  std::map<std::string, double> default_parameters;  ///< 'Q' (last value per name)
  std::vector<Subscription> subscriptions;    ///< in order of their 'A' messages
  std::vector<LogText> texts;
  std::vector<Dropout> dropouts;
  std::uint64_t dropout_ms = 0;
  std::uint64_t sync_messages = 0;
  std::uint64_t messages = 0;                 ///< accepted messages of every type
  std::uint64_t data_messages = 0;            ///< accepted 'D' messages kept in a subscription
  DamageStats damage;

  const InfoValue* find_info(std::string_view key) const;
  /// The info value as text ("" when absent).
  std::string info_text(std::string_view key) const;
  /// The subscription of topic `name` and instance multi_id, or null.
  const Subscription* find(std::string_view name, int multi_id = 0) const;
  const std::uint8_t* payload(const DataRef& d) const { return bytes.data() + d.offset; }
};

/// Parses the bytes of a ULog file. Throws std::runtime_error when they are not a ULog (fewer
/// than 16 bytes, wrong magic) or set incompatible flags other than kIncompatDataAppended.
File parse(std::vector<std::uint8_t> bytes, const Limits& limits = {});
/// Reads and parses a file; throws std::runtime_error naming the file when it cannot be read, is
/// larger than limits.max_file_bytes, or parse() throws.
File read(const std::string& path, const Limits& limits = {});

/// Element `index` of field f of one data message as a double: NaN when the field is not a
/// number (char, nested), index >= f.count, or the message is too short for it.
double value(const File& file, const DataRef& d, const Field& f, std::uint32_t index = 0);
/// The same for 64-bit unsigned fields (timestamps) without the loss of precision of a double;
/// 0 when the field is not an integer type or the message is too short.
std::uint64_t value_u64(const File& file, const DataRef& d, const Field& f);

}  // namespace tools::ulog
