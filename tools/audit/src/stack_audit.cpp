#include "tools/stack_audit.hpp"

#include <cxxabi.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <tuple>
#include <stdexcept>

namespace tools::stack {

const char* to_string(FrameKind k) {
  switch (k) {
    case FrameKind::kStatic: return "static";
    case FrameKind::kDynamic: return "dynamic";
    case FrameKind::kDynamicBounded: return "dynamic,bounded";
  }
  return "?";
}

namespace {

bool parse_kind(const std::string& s, FrameKind& k);

/// A decimal byte count (1 to 15 digits).
bool parse_bytes(const std::string& s, long& out) {
  if (s.empty() || s.size() > 15) return false;
  long v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + (c - '0');
  }
  out = v;
  return true;
}

/// GCC's "<N> bytes (<qualifier>)" of a .ci label.
bool parse_usage(const std::string& s, long& bytes, FrameKind& kind) {
  const std::string mid = " bytes (";
  const std::size_t p = s.find(mid);
  if (p == std::string::npos || s.size() < p + mid.size() + 2 || s.back() != ')') return false;
  return parse_bytes(s.substr(0, p), bytes) &&
         parse_kind(s.substr(p + mid.size(), s.size() - p - mid.size() - 1), kind);
}

/// Length of the leading "file:line:col" of a .su line (the first ":<digits>:<digits>:"), or 0.
std::size_t su_location_length(const std::string& s) {
  const auto digits = [&s](std::size_t i) {
    std::size_t j = i;
    while (j < s.size() && s[j] >= '0' && s[j] <= '9') ++j;
    return j - i;
  };
  for (std::size_t i = s.find(':'); i != std::string::npos; i = s.find(':', i + 1)) {
    const std::size_t a = digits(i + 1);
    if (a == 0 || i + 1 + a >= s.size() || s[i + 1 + a] != ':') continue;
    const std::size_t b = digits(i + 2 + a);
    if (b == 0 || i + 2 + a + b >= s.size() || s[i + 2 + a + b] != ':') continue;
    return i + 2 + a + b;
  }
  return 0;
}

bool parse_kind(const std::string& s, FrameKind& k) {
  if (s == "static") k = FrameKind::kStatic;
  else if (s == "dynamic") k = FrameKind::kDynamic;
  else if (s == "dynamic,bounded") k = FrameKind::kDynamicBounded;
  else return false;
  return true;
}

std::string record(const std::string& location, long bytes, FrameKind kind) {
  return location + " " + std::to_string(bytes) + " " + to_string(kind);
}

/// Minimal reader of GCC's VCG output: "node: { key: "value" ... }" / "edge: { ... }" lines inside
/// one "graph: { title: ... }". Values are double-quoted strings with backslash escapes, or bare
/// words (shape : ellipse).
class VcgReader {
 public:
  VcgReader(const std::string& text, const std::string& source) : s_(text), source_(source) {}

  bool read(CallGraph& g, std::string& err) {
    skip_ws();
    if (!keyword("graph") || !expect(':') || !expect('{')) return fail("expected 'graph: {'", err);
    bool closed = false;
    while (true) {
      skip_ws();
      if (pos_ >= s_.size()) break;
      if (s_[pos_] == '}') {
        ++pos_;
        closed = true;
        break;
      }
      std::string key;
      if (!word(key) || !expect(':')) return fail("expected 'key:'", err);
      if (key == "node" || key == "edge") {
        std::map<std::string, std::string> attrs;
        if (!block(attrs)) return fail("malformed " + key + " block", err);
        if (key == "node" ? !add_node(g, attrs, err) : !add_edge(g, attrs, err)) return false;
      } else {
        std::string value;  // graph attributes (title)
        if (!value_of(value)) return fail("malformed value of '" + key + "'", err);
      }
    }
    if (!closed) return fail("graph not closed", err);
    skip_ws();
    if (pos_ != s_.size()) return fail("text after the graph", err);
    ++g.units;
    return true;
  }

 private:
  bool fail(const std::string& what, std::string& err) {
    int line = 1 + static_cast<int>(std::count(s_.begin(), s_.begin() + static_cast<long>(std::min(pos_, s_.size())), '\n'));
    err = source_ + ":" + std::to_string(line) + ": " + what;
    return false;
  }
  void skip_ws() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool expect(char c) {
    skip_ws();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  bool word(std::string& w) {
    skip_ws();
    const std::size_t b = pos_;
    while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_')) ++pos_;
    w = s_.substr(b, pos_ - b);
    return !w.empty();
  }
  bool keyword(const char* k) {
    std::string w;
    return word(w) && w == k;
  }
  bool value_of(std::string& v) {
    skip_ws();
    if (pos_ >= s_.size()) return false;
    if (s_[pos_] != '"') return word(v);
    ++pos_;
    v.clear();
    while (pos_ < s_.size() && s_[pos_] != '"') {
      if (s_[pos_] == '\\' && pos_ + 1 < s_.size()) {
        const char e = s_[pos_ + 1];
        v += e == 'n' ? '\n' : e;  // VCG escapes: \n in labels, \" and \\ elsewhere
        pos_ += 2;
      } else {
        v += s_[pos_++];
      }
    }
    if (pos_ >= s_.size()) return false;
    ++pos_;
    return true;
  }
  bool block(std::map<std::string, std::string>& attrs) {
    if (!expect('{')) return false;
    while (true) {
      skip_ws();
      if (pos_ < s_.size() && s_[pos_] == '}') {
        ++pos_;
        return true;
      }
      std::string key, value;
      if (!word(key) || !expect(':') || !value_of(value)) return false;
      attrs[key] = value;
    }
  }

  bool add_node(CallGraph& g, const std::map<std::string, std::string>& a, std::string& err) {
    const auto t = a.find("title");
    const auto l = a.find("label");
    if (t == a.end() || t->second.empty() || l == a.end()) return fail("node without title or label", err);
    std::vector<std::string> lines;
    std::stringstream ss(l->second);
    for (std::string line; std::getline(ss, line, '\n');) lines.push_back(line);
    Function& f = g.functions[t->second];
    f.id = t->second;
    if (f.label.empty() && !lines.empty()) f.label = lines[0];
    if (f.location.empty() && lines.size() > 1) f.location = lines[1];
    if (lines.size() > 2) {
      long bytes = 0;
      FrameKind kind = FrameKind::kStatic;
      if (!parse_usage(lines[2], bytes, kind))
        return fail("unrecognised stack usage '" + lines[2] + "' of " + t->second, err);
      g.frame_records.push_back(record(lines.size() > 1 ? lines[1] : "", bytes, kind));
      if (!f.defined || bytes > f.frame_bytes) f.frame_bytes = bytes;
      if (!f.defined || kind != FrameKind::kStatic) {
        if (f.kind == FrameKind::kStatic || kind == FrameKind::kDynamic) f.kind = kind;
      }
      if (lines.size() > 1) f.location = lines[1];
      f.defined = true;
    }
    return true;
  }

  bool add_edge(CallGraph& g, const std::map<std::string, std::string>& a, std::string& err) {
    const auto s = a.find("sourcename");
    const auto t = a.find("targetname");
    if (s == a.end() || t == a.end() || s->second.empty() || t->second.empty())
      return fail("edge without sourcename or targetname", err);
    Function& from = g.functions[s->second];
    from.id = s->second;
    from.callees.insert(t->second);
    Function& to = g.functions[t->second];
    to.id = t->second;
    return true;
  }

  const std::string& s_;
  std::string source_;
  std::size_t pos_ = 0;
};

}  // namespace

bool parse_ci(const std::string& text, const std::string& source, CallGraph& g, std::string& err) {
  CallGraph local = g;
  VcgReader r(text, source);
  if (!r.read(local, err)) return false;
  g = std::move(local);
  return true;
}

void link(CallGraph& g) {
  std::map<std::string, std::vector<std::string>> defs;  // symbol -> "<file>:<symbol>" definitions
  for (const auto& [id, f] : g.functions) {
    const std::size_t colon = id.rfind(':');
    if (f.defined && colon != std::string::npos) defs[id.substr(colon + 1)].push_back(id);
  }
  for (auto& [id, f] : g.functions) {
    if (f.defined || id.find(':') != std::string::npos) continue;
    const auto d = defs.find(id);
    if (d == defs.end()) continue;
    f.linked = true;
    f.callees.insert(d->second.begin(), d->second.end());
  }
}

bool parse_su(const std::string& text, const std::string& source, std::vector<SuEntry>& out, std::string& err) {
  // "file:line:col:function<TAB>bytes<TAB>qualifier"; the function may contain ':' and spaces.
  std::stringstream ss(text);
  int n = 0;
  std::vector<SuEntry> add;
  for (std::string line; std::getline(ss, line);) {
    ++n;
    if (line.empty()) continue;
    SuEntry e;
    const std::size_t t2 = line.rfind('\t');
    const std::size_t t1 = t2 == std::string::npos || t2 == 0 ? std::string::npos : line.rfind('\t', t2 - 1);
    const std::string head = t1 == std::string::npos ? "" : line.substr(0, t1);
    const std::size_t loc = su_location_length(head);
    if (t1 == std::string::npos || loc == 0 || !parse_bytes(line.substr(t1 + 1, t2 - t1 - 1), e.bytes) ||
        !parse_kind(line.substr(t2 + 1), e.kind)) {
      err = source + ":" + std::to_string(n) + ": not a stack-usage line: " + line.substr(0, 200);
      return false;
    }
    e.location = head.substr(0, loc);
    e.function = head.substr(loc + 1);
    add.push_back(std::move(e));
  }
  out.insert(out.end(), add.begin(), add.end());
  return true;
}

std::vector<std::string> cross_check(const CallGraph& g, const std::vector<SuEntry>& su) {
  std::map<std::string, int> count;  // + for .ci, - for .su
  for (const std::string& r : g.frame_records) ++count[r];
  for (const SuEntry& e : su) --count[record(e.location, e.bytes, e.kind)];
  std::vector<std::string> diff;
  for (const auto& [r, c] : count) {
    if (c > 0) diff.push_back(".ci only (x" + std::to_string(c) + "): " + r);
    if (c < 0) diff.push_back(".su only (x" + std::to_string(-c) + "): " + r);
  }
  return diff;
}

const std::vector<ExternalCost>& external_costs() {
  // Host x86-64, glibc 2.36 (Debian 12), symbols already bound (the first call through a lazily
  // bound PLT entry runs the dynamic linker's resolver, about 3 KiB more; flight builds link
  // statically). Measured by tests/unit/test_stack_audit.cpp (LibraryCostsBoundMeasuredUse): each
  // function called on a painted thread stack with ordinary, huge (slow argument reduction),
  // tiny, infinite and NaN arguments; the deepest use seen, including the call's return address,
  // was 8 ... 176 bytes for the libm functions and at most 8 for mem*. The table takes a
  // margin of about 3x over those and the test keeps it an upper bound on the machine it runs on.
  static const std::vector<ExternalCost> kCosts = [] {
    std::vector<ExternalCost> v;
    const char* libm_basis = "assumed: glibc libm leaf, measured <= 176 B on a painted stack (test_stack_audit)";
    for (const char* f : {"sin", "cos", "tan", "sincos", "exp", "log", "sqrt", "atan", "atan2", "asin", "acos", "pow",
                          "hypot", "fmod", "sinh", "cosh", "tanh", "log10", "exp2", "cbrt", "lround"})
      v.push_back({f, 512, libm_basis});
    const char* mem_basis = "assumed: glibc string routine (assembly, no frame), measured <= 8 B (test_stack_audit)";
    for (const char* f : {"memset", "memcpy", "memmove", "memcmp"}) v.push_back({f, 64, mem_basis});
    return v;
  }();
  return kCosts;
}

bool is_heap_function(const std::string& id) {
  static const std::set<std::string> kHeap = {
      "malloc", "calloc", "realloc", "free", "aligned_alloc", "posix_memalign", "memalign", "valloc", "pvalloc",
      "_Znwm", "_Znam", "_ZdlPv", "_ZdaPv", "_ZdlPvm", "_ZdaPvm", "_ZnwmSt11align_val_t", "_ZnamSt11align_val_t",
      "_ZdlPvSt11align_val_t", "_ZdaPvSt11align_val_t", "_ZdlPvmSt11align_val_t", "_ZdaPvmSt11align_val_t",
      "_ZnwmRKSt9nothrow_t", "_ZnamRKSt9nothrow_t", "_Znwj", "_Znaj", "_ZdlPvj", "_ZdaPvj"};
  return kHeap.count(id) != 0;
}

std::string demangle(const std::string& id) {
  // File-local symbols: "<file>:<symbol>"; clones: "<symbol>.constprop.0" (the demangler keeps
  // the suffix as " [clone .constprop.0]").
  const std::size_t colon = id.rfind(':');
  const std::string prefix = colon == std::string::npos ? "" : id.substr(0, colon + 1);
  const std::string sym = colon == std::string::npos ? id : id.substr(colon + 1);
  int status = -1;  // only mangled names: the demangler also decodes bare type codes ("a" is signed char)
  std::unique_ptr<char, void (*)(void*)> d(
      sym.rfind("_Z", 0) == 0 ? abi::__cxa_demangle(sym.c_str(), nullptr, nullptr, &status) : nullptr, std::free);
  const std::string file = prefix.empty() ? "" : std::filesystem::path(prefix.substr(0, prefix.size() - 1)).filename().string();
  const std::string name = status == 0 && d ? std::string(d.get()) : sym;
  return file.empty() ? name : name + " [" + file + "]";
}

std::string compact_name(const std::string& demangled) {
  std::string s = demangled;
  auto strip_suffix = [&s]() {
    while (!s.empty() && s.back() == ' ') s.pop_back();
    if (!s.empty() && s.back() == ']') {  // " [clone .constprop.0]", " [ekf.cpp]"
      const std::size_t b = s.rfind(" [");
      if (b != std::string::npos) {
        s.erase(b);
        return true;
      }
    }
    for (const char* q : {" const", " volatile", " &&", " &"}) {
      const std::string t(q);
      if (s.size() > t.size() && s.compare(s.size() - t.size(), t.size(), t) == 0) {
        s.erase(s.size() - t.size());
        return true;
      }
    }
    return false;
  };
  while (strip_suffix()) {
  }
  if (s.empty() || s.back() != ')') return s;
  int depth = 0;
  for (std::size_t i = s.size(); i-- > 0;) {
    if (s[i] == ')') ++depth;
    if (s[i] == '(' && --depth == 0) return s.substr(0, i);
  }
  return s;
}

std::vector<std::pair<std::string, std::string>> layout_aliases(const CallGraph& g) {
  std::vector<std::pair<std::string, std::string>> a;
  for (const std::string& l : fsw_layouts()) {
    const auto w = g.functions.find("sdins_stack_entry_tick_" + l);
    if (w == g.functions.end() || w->second.callees.size() != 1) continue;
    const std::string d = demangle(*w->second.callees.begin());
    const std::string head = "fsw::Executive<", tail = ">::tick(";
    const std::size_t b = d.find(head), e = d.rfind(tail);
    if (b == std::string::npos || e == std::string::npos || e <= b + head.size()) continue;
    a.emplace_back(d.substr(b + head.size(), e - b - head.size()), l);
  }
  // Longest first: a layout's spelling may contain another's (ConsiderLayout<ErrorStateLayout<...>>).
  std::sort(a.begin(), a.end(), [](const auto& x, const auto& y) { return x.first.size() > y.first.size(); });
  return a;
}

std::string with_aliases(std::string s, const std::vector<std::pair<std::string, std::string>>& aliases) {
  for (const auto& [from, to] : aliases)
    for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size())) s.replace(p, from.size(), to);
  return s;
}

std::string single_callee(const CallGraph& g, const std::string& wrapper) {
  const auto it = g.functions.find(wrapper);
  if (it == g.functions.end() || !it->second.defined)
    throw std::runtime_error("stack audit: entry wrapper '" + wrapper + "' is not in the call graph");
  if (it->second.callees.size() != 1)
    throw std::runtime_error("stack audit: entry wrapper '" + wrapper + "' has " +
                             std::to_string(it->second.callees.size()) + " callees, expected exactly one");
  return *it->second.callees.begin();
}

namespace {
/// One function's state in the audit's depth-first search.
struct Info {
  int state = 0;  // 0 unvisited, 1 on the DFS stack, 2 done
  long depth = 0;
  std::string next;  // deepest callee
  std::set<std::string> reasons;
  std::set<std::string> assumed;
  std::string note;
};

/// A task's result read off the finished search: depth, findings with the chain that first
/// reached each, assumed externals, budget, and the deepest path (references shown as the
/// definitions they resolved to).
TaskResult task_result(const CallGraph& g, const TaskSpec& spec, std::map<std::string, Info>& info,
                       std::map<std::string, std::vector<std::string>>& via) {
  TaskResult r;
  r.name = spec.name;
  r.root = spec.root;
  r.description = spec.description;
  const Info& root = info[spec.root];
  r.stack_bytes = root.depth;
  r.unbounded_reasons.assign(root.reasons.begin(), root.reasons.end());
  r.bounded = r.unbounded_reasons.empty();
  for (const std::string& why : r.unbounded_reasons) {
    Finding fd;
    fd.reason = why;
    for (const std::string& id : via[why])
      if (!g.functions.at(id).linked) fd.via.push_back(id);
    r.findings.push_back(fd);
  }
  r.assumed_externals.assign(root.assumed.begin(), root.assumed.end());
  r.budget_bytes = spec.budget_bytes;
  r.within_budget = spec.budget_bytes <= 0 || (r.bounded && r.stack_bytes <= spec.budget_bytes);
  r.functions_reached = static_cast<int>(std::count_if(info.begin(), info.end(), [](const auto& kv) { return kv.second.state == 2; }));
  for (std::string id = spec.root; !id.empty();) {
    const Function& f = g.functions.at(id);
    const Info& in = info[id];
    if (f.linked) {  // a reference: show the definition it resolved to
      id = in.next;
      continue;
    }
    PathStep s;
    s.id = id;
    s.name = demangle(id);
    s.frame_bytes = f.defined ? f.frame_bytes + (f.callees.empty() ? spec.red_zone_bytes : 0) : in.depth;
    s.note = in.note;
    r.path.push_back(s);
    if (r.path.size() > g.functions.size()) break;  // cannot happen: next never points back up
    id = in.next;
  }
  return r;
}
}  // namespace

TaskResult analyse(const CallGraph& g, const TaskSpec& spec, const std::vector<ExternalCost>& costs) {
  if (g.functions.find(spec.root) == g.functions.end())
    throw std::runtime_error("stack audit: task '" + spec.name + "': root '" + spec.root + "' is not in the call graph");
  std::set<std::string> cut = spec.cut;  // a cut reference also cuts the definitions it links to
  for (const std::string& c : spec.cut)
    if (const auto it = g.functions.find(c); it != g.functions.end() && it->second.linked)
      cut.insert(it->second.callees.begin(), it->second.callees.end());
  std::map<std::string, const ExternalCost*> cost_of;
  for (const ExternalCost& c : costs) cost_of[c.name] = &c;

  std::map<std::string, Info> info;
  std::vector<std::string> stack;
  std::map<std::string, std::vector<std::string>> via;  // reason -> call chain that first reached it
  auto found = [&](Info& in, const std::string& reason, const std::string& extra) {
    in.reasons.insert(reason);
    if (via.count(reason)) return;
    std::vector<std::string> chain = stack;
    if (!extra.empty()) chain.push_back(extra);
    via[reason] = chain;
  };

  // Recursive DFS: the call graphs audited here are a few hundred functions deep at most.
  std::function<void(const std::string&)> visit = [&](const std::string& id) {
    Info& in = info[id];
    in.state = 1;
    stack.push_back(id);
    const Function& f = g.functions.at(id);
    long own = 0;
    if (f.linked) {
      in.note = "linked";
    } else if (f.defined) {
      own = f.frame_bytes;
      if (f.kind != FrameKind::kStatic) {
        found(in, std::string(to_string(f.kind)) + " stack frame (alloca / variable-length array) in " + demangle(id), "");
        in.note = to_string(f.kind);
      }
    } else if (const auto c = cost_of.find(id); c != cost_of.end()) {
      own = c->second->bytes;
      in.assumed.insert(id + " (" + std::to_string(own) + " B)");
      in.note = "assumed external cost";
    } else {
      found(in, "no stack information for " + demangle(id), "");
      in.note = "no stack information";
    }
    if (f.defined && !f.linked && f.callees.empty()) own += spec.red_zone_bytes;
    long best = 0;
    for (const std::string& c : f.callees) {
      if (cut.count(c)) continue;
      if (c == kIndirectCall) {
        found(in, "indirect call (function pointer or virtual) in " + demangle(id), "");
        continue;
      }
      if (is_heap_function(c)) {
        found(in, "heap call " + c + " in " + demangle(id), c);
        continue;
      }
      Info& ci = info[c];
      if (ci.state == 1) {  // back edge: recursion through every function from c to id
        std::string cycle;
        const auto from = std::find(stack.begin(), stack.end(), c);
        for (auto s = from; s != stack.end(); ++s) cycle += demangle(*s) + " -> ";
        found(in, "recursion: " + cycle + demangle(c), c);
        continue;
      }
      if (ci.state == 0) visit(c);
      const Info& done = info[c];
      in.reasons.insert(done.reasons.begin(), done.reasons.end());
      in.assumed.insert(done.assumed.begin(), done.assumed.end());
      if (in.next.empty() || done.depth > best) {
        best = done.depth;
        in.next = c;
      }
    }
    in.depth = own + best;
    in.state = 2;
    stack.pop_back();
  };
  visit(spec.root);

  return task_result(g, spec, info, via);
}

namespace {
std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw std::runtime_error("stack audit: cannot read " + p.string());
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

BuildData load_build_dir(const std::string& dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir)) throw std::runtime_error("stack audit: no build directory " + dir);
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file() && (e.path().extension() == ".ci" || e.path().extension() == ".su")) files.push_back(e.path());
  std::sort(files.begin(), files.end());  // deterministic merge order
  BuildData b;
  for (const fs::path& p : files) {
    std::string err;
    if (p.extension() == ".ci") {
      if (!parse_ci(read_file(p), p.string(), b.graph, err)) throw std::runtime_error("stack audit: " + err);
      ++b.ci_files;
    } else {
      if (!parse_su(read_file(p), p.string(), b.su, err)) throw std::runtime_error("stack audit: " + err);
      ++b.su_files;
    }
  }
  link(b.graph);
  if (b.ci_files == 0 || b.su_files == 0)
    throw std::runtime_error("stack audit: no .ci/.su files under " + dir + " (not a stack-audit build?)");
  return b;
}

const std::vector<std::string>& fsw_layouts() {
  static const std::vector<std::string> kLayouts = {"Layout15", "Layout24", "Layout15Full", "Layout24Full"};
  return kLayouts;
}

void fsw_task_specs(const CallGraph& g, long budget_bytes, long red_zone_bytes, std::vector<TaskSpec>& tasks,
                    std::vector<TaskSpec>& functions) {
  const std::string w = "sdins_stack_entry_";
  for (const std::string& l : fsw_layouts()) {
    const std::string tick = single_callee(g, w + "tick_" + l);
    const std::string propagate = single_callee(g, w + "propagate_" + l);
    const std::string update = single_callee(g, w + "update_" + l);
    const std::string update_pvt = single_callee(g, w + "update_pvt_" + l);
    const std::string feedback = single_callee(g, w + "feedback_" + l);
    const std::string accumulate = single_callee(g, w + "accumulate_" + l);
    const std::string ekf_group = single_callee(g, w + "ekf_group_" + l);
    TaskSpec mech;
    mech.name = "mech_200hz/" + l;
    mech.root = tick;
    mech.cut = {ekf_group};
    mech.budget_bytes = budget_bytes;
    mech.red_zone_bytes = red_zone_bytes;
    mech.description = "the 200 Hz group: Executive<" + l +
                       ">::tick (compensation, strapdown, transition accumulation, release, landing a correction; "
                       "the inline call of the 1 Hz group cut: it is the next task)";
    tasks.push_back(mech);
    TaskSpec ekf;
    ekf.name = "ekf_1hz/" + l;
    ekf.root = ekf_group;
    ekf.budget_bytes = budget_bytes;
    ekf.red_zone_bytes = red_zone_bytes;
    ekf.description = "the 1 Hz group: Executive<" + l +
                      ">::run_ekf_group (Ekf::propagate over the released interval, update or update_pvt, the "
                      "correction), on its own stack when it runs as its own task";
    tasks.push_back(ekf);
    for (const auto& [what, id] : {std::pair<std::string, std::string>{"accumulate", accumulate},
                                   {"propagate", propagate}, {"update", update}, {"update_pvt", update_pvt},
                                   {"feedback", feedback}}) {
      TaskSpec f;
      f.name = "Ekf<" + l + ">::" + what;
      f.root = id;
      f.red_zone_bytes = red_zone_bytes;
      functions.push_back(f);
    }
  }
  // The flight application's entries for the layouts that fly (HIL, SIL, replay): every path the
  // flight code takes from an input event, the initialisation included.
  for (const std::string l : {"Layout15Full", "Layout24Full"}) {
    const std::string app = "FlightApp<" + l + ">::";
    for (const auto& [task, entry, what] :
         {std::tuple<std::string, std::string, std::string>{
              "imu_input", "on_imu_",
              "on_imu (levelling / alignment before initialisation; batching and, on a frame's last sample, "
              "Executive::tick with the 200 Hz group and the 1 Hz group when due)"},
          {"gnss_input", "on_gnss_",
           "on_gnss (raw epoch -> satellite positions from the almanac; before initialisation the single-point "
           "solution and the initialisation it may complete)"},
          {"pvt_input", "on_gnss_pvt_", "on_gnss_pvt (validation; initialisation from a solution)"},
          {"event_input", "on_event_",
           "on_event, the one entry every harness calls (SIL, HIL, replay, Monte Carlo, audits, diagnosis, the "
           "Cortex-M7 image): dispatches an fsw::InputEvent to on_imu, on_gnss, on_gnss_pvt or on_almanac"}}) {
      TaskSpec t;
      t.name = task + "/" + l;
      t.root = single_callee(g, w + entry + l);
      t.budget_bytes = budget_bytes;
      t.red_zone_bytes = red_zone_bytes;
      t.description = app + what;
      tasks.push_back(t);
    }
  }
  for (const auto& [name, wrapper] : {std::pair<std::string, std::string>{"Strapdown::step", "strapdown_step"},
                                      {"FrameBuilder::add", "frame_builder_add"}}) {
    TaskSpec f;
    f.name = name;
    f.root = single_callee(g, w + wrapper);
    f.red_zone_bytes = red_zone_bytes;
    functions.push_back(f);
  }
}

std::vector<SelfCheck> self_check(const CallGraph& g, const std::vector<ExternalCost>& costs, long red_zone_bytes) {
  const std::string p = "sdins_stack_fixture_";
  std::vector<SelfCheck> out;
  auto run = [&](const std::string& fixture, const std::string& expect,
                 const std::function<bool(const TaskResult&, std::string&)>& ok) {
    SelfCheck c;
    c.fixture = fixture;
    c.expect = expect;
    try {
      TaskSpec s;
      s.name = fixture;
      s.root = p + fixture;
      s.red_zone_bytes = red_zone_bytes;
      const TaskResult r = analyse(g, s, costs);
      c.pass = ok(r, c.detail);
      if (c.detail.empty()) {
        c.detail = std::to_string(r.stack_bytes) + " B, " + (r.bounded ? "bounded" : "unbounded");
        for (const std::string& why : r.unbounded_reasons) c.detail += "; " + why.substr(0, 160);
      }
    } catch (const std::exception& e) {
      c.pass = false;
      c.detail = e.what();
    }
    out.push_back(c);
  };
  auto reason = [](const TaskResult& r, const std::string& what) {
    return std::any_of(r.unbounded_reasons.begin(), r.unbounded_reasons.end(),
                       [&](const std::string& s) { return s.find(what) != std::string::npos; });
  };
  auto frame = [&](const std::string& f) {
    const auto it = g.functions.find(p + f);
    return it == g.functions.end() || !it->second.defined ? -1L : it->second.frame_bytes;
  };
  run("diamond", "bounded; deepest path diamond -> big -> leaf; stack = sum of those frames + red zone",
      [&](const TaskResult& r, std::string& d) {
        const long want = frame("diamond") + frame("big") + frame("leaf") + red_zone_bytes;
        const bool path = r.path.size() == 3 && r.path[1].id == p + "big" && r.path[2].id == p + "leaf";
        d = std::to_string(r.stack_bytes) + " B (expected " + std::to_string(want) + "), path via " +
            (r.path.size() > 1 ? r.path[1].id : std::string("?"));
        return r.bounded && path && r.stack_bytes == want && frame("small") > 0 && frame("big") >= 3072;
      });
  run("recursion", "unbounded: recursion", [&](const TaskResult& r, std::string&) { return !r.bounded && reason(r, "recursion"); });
  run("indirect", "unbounded: indirect call", [&](const TaskResult& r, std::string&) { return !r.bounded && reason(r, "indirect call"); });
  run("alloca", "unbounded: dynamic frame", [&](const TaskResult& r, std::string&) { return !r.bounded && reason(r, "dynamic"); });
  run("external", "unbounded: no stack information for sdins_stack_fixture_undefined",
      [&](const TaskResult& r, std::string&) { return !r.bounded && reason(r, "no stack information for sdins_stack_fixture_undefined"); });
  run("eigen_product", "unbounded: Eigen general matrix product (dynamic frame or heap)",
      [&](const TaskResult& r, std::string&) {
        return !r.bounded && (reason(r, "dynamic") || reason(r, "heap")) && reason(r, "general_matrix_matrix_product");
      });
  return out;
}

}  // namespace tools::stack
