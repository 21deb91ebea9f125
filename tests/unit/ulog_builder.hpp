// Handcrafted ULog files for the tests (tools/ulog.hpp): a writer of the format's messages, built
// from the specification, so that the reader's tests control every byte (including damage).
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace test {

class UlogBuilder {
 public:
  explicit UlogBuilder(std::uint64_t start_us = 1000) {
    const std::uint8_t magic[] = {0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01};
    bytes.insert(bytes.end(), magic, magic + 8);
    put64(start_us);
  }

  std::vector<std::uint8_t> bytes;

  /// A raw message: header (size, type) and payload.
  void message(char type, const std::vector<std::uint8_t>& payload) {
    put16(static_cast<std::uint16_t>(payload.size()));
    bytes.push_back(static_cast<std::uint8_t>(type));
    bytes.insert(bytes.end(), payload.begin(), payload.end());
  }
  void flag_bits(std::uint8_t incompat0 = 0, std::uint64_t appended0 = 0) {
    std::vector<std::uint8_t> p(40, 0);
    p[8] = incompat0;
    for (int i = 0; i < 8; ++i) p[static_cast<std::size_t>(16 + i)] = static_cast<std::uint8_t>(appended0 >> (8 * i));
    message('B', p);
  }
  void format(const std::string& text) { message('F', str(text)); }
  void info(const std::string& key, const std::vector<std::uint8_t>& value) {
    std::vector<std::uint8_t> p{static_cast<std::uint8_t>(key.size())};
    append(p, str(key));
    append(p, value);
    message('I', p);
  }
  void info_text(const std::string& name, const std::string& text) {
    info("char[" + std::to_string(text.size()) + "] " + name, str(text));
  }
  void multi_info(bool continued, const std::string& key, const std::string& text) {
    std::vector<std::uint8_t> p{static_cast<std::uint8_t>(continued ? 1 : 0), static_cast<std::uint8_t>(key.size())};
    append(p, str(key));
    append(p, str(text));
    message('M', p);
  }
  void param_float(const std::string& name, float v) {
    const std::string key = "float " + name;
    std::vector<std::uint8_t> p{static_cast<std::uint8_t>(key.size())};
    append(p, str(key));
    append(p, pod(v));
    message('P', p);
  }
  void param_int(const std::string& name, std::int32_t v) {
    const std::string key = "int32_t " + name;
    std::vector<std::uint8_t> p{static_cast<std::uint8_t>(key.size())};
    append(p, str(key));
    append(p, pod(v));
    message('P', p);
  }
  void add(std::uint8_t multi_id, std::uint16_t msg_id, const std::string& name) {
    std::vector<std::uint8_t> p{multi_id, static_cast<std::uint8_t>(msg_id & 0xff), static_cast<std::uint8_t>(msg_id >> 8)};
    append(p, str(name));
    message('A', p);
  }
  /// A data message: msg_id, then the fields' bytes (the caller packs them in format order).
  void data(std::uint16_t msg_id, const std::vector<std::uint8_t>& fields) {
    std::vector<std::uint8_t> p{static_cast<std::uint8_t>(msg_id & 0xff), static_cast<std::uint8_t>(msg_id >> 8)};
    append(p, fields);
    message('D', p);
  }
  void sync() { message('S', {0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12}); }
  void dropout(std::uint16_t ms) { message('O', pod(ms)); }
  void text(std::uint64_t ts, const std::string& t) {
    std::vector<std::uint8_t> p{'6'};
    append(p, pod(ts));
    append(p, str(t));
    message('L', p);
  }

  template <class T>
  static std::vector<std::uint8_t> pod(const T& v) {
    std::vector<std::uint8_t> b(sizeof(T));
    std::memcpy(b.data(), &v, sizeof(T));
    return b;
  }
  static std::vector<std::uint8_t> str(const std::string& s) { return {s.begin(), s.end()}; }
  static void append(std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) { a.insert(a.end(), b.begin(), b.end()); }

 private:
  void put16(std::uint16_t v) { append(bytes, pod(v)); }
  void put64(std::uint64_t v) { append(bytes, pod(v)); }
};

/// Packs fields in order: Pack().u64(t).f32(x)... .bytes
struct Pack {
  std::vector<std::uint8_t> bytes;
  template <class T>
  Pack& put(T v) {
    UlogBuilder::append(bytes, UlogBuilder::pod(v));
    return *this;
  }
  Pack& u64(std::uint64_t v) { return put(v); }
  Pack& i32(std::int32_t v) { return put(v); }
  Pack& u32(std::uint32_t v) { return put(v); }
  Pack& u16(std::uint16_t v) { return put(v); }
  Pack& u8(std::uint8_t v) { return put(v); }
  Pack& f32(float v) { return put(v); }
  Pack& f64(double v) { return put(v); }
};

}  // namespace test
