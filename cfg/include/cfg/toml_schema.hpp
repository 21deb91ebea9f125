// The project's TOML schema reader: the toml++ 3.3.0 defences, value ranges, and a reader base
// whose subclasses describe a schema as tables of keys with handlers. Every key is optional,
// unknown keys are rejected, and each error reads "<source>:<line>:<col>: <message naming the
// dotted key path>". Used by the flight configuration files (cfg/src/flight_config.cpp) and the
// scenario files (sim/src/scenario.cpp), so both speak the same rules and error format.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <toml++/toml.h>

namespace cfg::toml_schema {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

std::string format_number(double v);

/// A validity interval; infinite bounds mean "unbounded" (values must be finite regardless).
struct Range {
  double lo = -kInf;
  double hi = kInf;
  bool lo_open = false;
  bool hi_open = false;

  bool contains(double v) const {
    return std::isfinite(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  std::string text() const {
    if (std::isinf(lo) && std::isinf(hi)) return "a finite number";
    if (std::isinf(hi)) return std::string("a finite number ") + (lo_open ? "> " : ">= ") + format_number(lo);
    return std::string("a number in ") + (lo_open ? "(" : "[") + format_number(lo) + ", " + format_number(hi) +
           (hi_open ? ")" : "]");
  }
};

constexpr Range closed(double lo, double hi) { return {lo, hi, false, false}; }
constexpr Range left_open(double lo, double hi) { return {lo, hi, true, false}; }
constexpr Range right_open(double lo, double hi) { return {lo, hi, false, true}; }
constexpr Range non_negative() { return {0.0, kInf, false, false}; }
constexpr Range positive() { return {0.0, kInf, true, false}; }

/// " (got <value>)" for error messages.
std::string got(const toml::node& n);

/// Parses a TOML document with the toml++ 3.3.0 defences (toml_schema.cpp). Returns false with the
/// error as "<source>:<line>:<col>: <message>".
bool parse_document(const std::string& text, const std::string& source, toml::table& root, std::string& error);

/// Base of the schema readers: the handlers of one table's keys, errors with their position.
class Reader {
 public:
  using Handler = std::function<bool(const toml::node&, const std::string& path)>;
  struct Field {
    std::string_view key;
    Handler handle;
  };

  explicit Reader(std::string source) : source_(std::move(source)) {}
  const std::string& error() const { return error_; }

 protected:
  /// Records the error at the node's (or key's) position; returns false so callers can `return fail(...)`.
  template <typename Located>
  bool fail(const Located& where, const std::string& message) {
    const toml::source_position& pos = where.source().begin;
    error_ = source_ + ":" + std::to_string(pos.line) + ":" + std::to_string(pos.column) + ": " + message;
    return false;
  }

  /// Runs the handler of each key of t; a key without a handler is rejected.
  bool fields(const toml::table& t, const std::string& prefix, std::initializer_list<Field> known) {
    for (auto&& [key, node] : t) {
      const std::string path = prefix + std::string(key.str());
      // Compared through a named copy: clang before 16 cannot capture a structured binding.
      const std::string_view name = key.str();
      const auto field = std::find_if(known.begin(), known.end(), [&](const Field& f) { return f.key == name; });
      if (field == known.end()) return fail(key, "unknown key '" + path + "'");
      if (!field->handle(node, path)) return false;
    }
    return true;
  }

  const toml::table* table(const toml::node& n, const std::string& path) {
    if (const auto* t = n.as_table()) return t;
    fail(n, "'" + path + "' must be a table" + got(n));
    return nullptr;
  }

  bool read_number(const toml::node& n, const std::string& path, Range range, double& out) {
    const std::optional<double> v = n.is_number() ? n.value<double>() : std::nullopt;
    if (!v || !range.contains(*v)) return fail(n, "'" + path + "' must be " + range.text() + got(n));
    out = *v;
    return true;
  }

  Handler number(double& out, Range range) {
    return [this, &out, range](const toml::node& n, const std::string& p) { return read_number(n, p, range, out); };
  }

  /// An integer key (a float such as 12.0 is rejected) in [lo, hi].
  Handler integer(int& out, int lo, int hi) {
    return [this, &out, lo, hi](const toml::node& n, const std::string& p) {
      const auto* v = n.as_integer();
      if (!v || v->get() < lo || v->get() > hi) {
        return fail(n, "'" + p + "' must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]" +
                           got(n));
      }
      out = static_cast<int>(v->get());
      return true;
    };
  }

  template <typename E>
  Handler choice(E& out, std::vector<std::pair<std::string_view, E>> options) {
    return [this, &out, options](const toml::node& n, const std::string& p) {
      std::string expected;
      for (std::size_t i = 0; i < options.size(); ++i) {
        const auto& [name, value] = options[i];
        if (const auto* s = n.as_string(); s && s->get() == name) {
          out = value;
          return true;
        }
        expected += (i == 0 ? "" : i + 1 == options.size() ? " or " : ", ") + ("\"" + std::string(name) + "\"");
      }
      return fail(n, "'" + p + "' must be " + expected + got(n));
    };
  }

  Handler text(std::string& out) {
    return [this, &out](const toml::node& n, const std::string& p) {
      const auto* v = n.as_string();
      if (!v) return fail(n, "'" + p + "' must be a string" + got(n));
      out = v->get();
      return true;
    };
  }

  Handler boolean(bool& out) {
    return [this, &out](const toml::node& n, const std::string& p) {
      const auto* v = n.as_boolean();
      if (!v) return fail(n, "'" + p + "' must be true or false" + got(n));
      out = v->get();
      return true;
    };
  }

  /// A key that was renamed: rejected with a message that names its new spelling (the old name
  /// lacked its unit, say), so a file written for the old schema fails clearly instead of as an
  /// unknown key.
  Handler renamed(std::string_view new_key) {
    return [this, new_key](const toml::node& n, const std::string& p) {
      const std::size_t dot = p.rfind('.');
      const std::string new_path = (dot == std::string::npos ? "" : p.substr(0, dot + 1)) + std::string(new_key);
      return fail(n, "'" + p + "' was renamed to '" + new_path + "' (the same value and unit)");
    };
  }

  /// An array of three numbers, each in range.
  template <typename Vec>
  Handler vector3(Vec& out, Range range) {
    return [this, &out, range](const toml::node& n, const std::string& p) {
      const auto* a = n.as_array();
      if (!a || a->size() != 3) return fail(n, "'" + p + "' must be an array of 3 numbers" + got(n));
      Vec v = out;
      for (std::size_t i = 0; i < 3; ++i) {
        if (!read_number(*a->get(i), p + "[" + std::to_string(i) + "]", range, v[static_cast<int>(i)])) return false;
      }
      out = v;
      return true;
    };
  }

  std::string source_;
  std::string error_;
};

}  // namespace cfg::toml_schema
