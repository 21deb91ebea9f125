// The stack audit's call-graph computation (tools/stack_audit.hpp) on small synthetic .ci/.su
// inputs written in GCC's format, so the algorithm is proved independently of the real build:
// a diamond, recursion (direct and mutual), indirect calls, dynamic frames, heap calls, library
// functions with and without assumed costs, cut edges, COMDAT linking across TUs, the red zone,
// and malformed input. The last test checks the assumed library costs against a measurement.
#include <gtest/gtest.h>
#include <pthread.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "tools/stack_audit.hpp"

namespace {

using namespace tools::stack;

/// One TU's .ci text in GCC 12's format.
class Ci {
 public:
  explicit Ci(std::string tu) : tu_(std::move(tu)) {}
  Ci& def(const std::string& title, long bytes, const std::string& kind = "static", int line = 1) {
    body_ += "node: { title: \"" + title + "\" label: \"" + title + "()\\n" + tu_ + ":" + std::to_string(line) +
             ":5\\n" + std::to_string(bytes) + " bytes (" + kind + ")\" }\n";
    su_ += tu_ + ":" + std::to_string(line) + ":5:" + title + "()\t" + std::to_string(bytes) + "\t" + kind + "\n";
    return *this;
  }
  Ci& decl(const std::string& title) {
    body_ += "node: { title: \"" + title + "\" label: \"" + title + "\\n<built-in>\" shape : ellipse }\n";
    return *this;
  }
  Ci& call(const std::string& from, const std::string& to) {
    body_ += "edge: { sourcename: \"" + from + "\" targetname: \"" + to + "\" label: \"" + tu_ + ":9:1\" }\n";
    return *this;
  }
  std::string text() const { return "graph: { title: \"" + tu_ + "\"\n" + body_ + "}\n"; }
  const std::string& su() const { return su_; }

 private:
  std::string tu_, body_, su_;
};

CallGraph graph(const std::vector<Ci>& tus) {
  CallGraph g;
  for (const Ci& c : tus) {
    std::string err;
    EXPECT_TRUE(parse_ci(c.text(), "test.ci", g, err)) << err;
  }
  link(g);
  return g;
}

TaskResult run(const CallGraph& g, const std::string& root, std::set<std::string> cut = {}, long red_zone = 0,
               long budget = 0) {
  TaskSpec s;
  s.name = root;
  s.root = root;
  s.cut = std::move(cut);
  s.red_zone_bytes = red_zone;
  s.budget_bytes = budget;
  return analyse(g, s, external_costs());
}

bool has_reason(const TaskResult& r, const std::string& what) {
  for (const auto& s : r.unbounded_reasons)
    if (s.find(what) != std::string::npos) return true;
  return false;
}

std::vector<std::string> path_ids(const TaskResult& r) {
  std::vector<std::string> v;
  for (const auto& s : r.path) v.push_back(s.id);
  return v;
}

TEST(StackAudit, ParsesGccNodesEdgesAndStackUsage) {
  Ci a("a.cpp");
  a.def("main", 48).def("leaf", 16, "static", 7).decl("sin").call("main", "leaf").call("main", "sin");
  const CallGraph g = graph({a});
  ASSERT_EQ(g.functions.size(), 3u);
  const Function& m = g.functions.at("main");
  EXPECT_TRUE(m.defined);
  EXPECT_EQ(m.frame_bytes, 48);
  EXPECT_EQ(m.location, "a.cpp:1:5");
  EXPECT_EQ(m.callees, (std::set<std::string>{"leaf", "sin"}));
  EXPECT_FALSE(g.functions.at("sin").defined);
  EXPECT_EQ(g.units, 1);
  std::vector<SuEntry> su;
  std::string err;
  ASSERT_TRUE(parse_su(a.su(), "a.su", su, err)) << err;
  ASSERT_EQ(su.size(), 2u);
  EXPECT_EQ(su[1].location, "a.cpp:7:5");
  EXPECT_EQ(su[1].bytes, 16);
  EXPECT_TRUE(cross_check(g, su).empty());
}

TEST(StackAudit, RealGccLineWithColonsAndTemplatesParses) {
  const std::string ci =
      "graph: { title: \"/w/fsw/src/ekf.cpp\"\n"
      "node: { title: \"/w/fsw/src/ekf.cpp:_ZN3fsw3EkfI1LE6updateEv\" label: \"fsw::Status fsw::Ekf<Layout>::update() "
      "[with Layout = fsw::L]\\n/w/fsw/src/ekf.cpp:300:8\\n26272 bytes (static)\" }\n"
      "node: { title: \"/w/fsw/src/ekf.cpp:_ZN5Eigen3runEv.constprop.0\" label: \"static void Eigen::run()\\n"
      "/usr/include/eigen3/Eigen/src/Core/products/GeneralMatrixMatrix.h:61:13\\n320 bytes (dynamic)\" }\n"
      "edge: { sourcename: \"/w/fsw/src/ekf.cpp:_ZN3fsw3EkfI1LE6updateEv\" targetname: "
      "\"/w/fsw/src/ekf.cpp:_ZN5Eigen3runEv.constprop.0\" label: \"/usr/include/eigen3/x.h:230:14\" }\n"
      "}\n";
  const std::string su =
      "/w/fsw/src/ekf.cpp:300:8:fsw::Status fsw::Ekf<Layout>::update() [with Layout = fsw::L]\t26272\tstatic\n"
      "/usr/include/eigen3/Eigen/src/Core/products/GeneralMatrixMatrix.h:61:13:static void Eigen::run(Index, "
      "Eigen::internal::level3_blocking<LhsScalar, RhsScalar>&) [with Index = long int]\t320\tdynamic\n";
  CallGraph g;
  std::string err;
  ASSERT_TRUE(parse_ci(ci, "ekf.ci", g, err)) << err;
  std::vector<SuEntry> entries;
  ASSERT_TRUE(parse_su(su, "ekf.su", entries, err)) << err;
  EXPECT_TRUE(cross_check(g, entries).empty());
  EXPECT_EQ(entries[0].function, "fsw::Status fsw::Ekf<Layout>::update() [with Layout = fsw::L]");
  const TaskResult r = run(g, "/w/fsw/src/ekf.cpp:_ZN3fsw3EkfI1LE6updateEv");
  EXPECT_EQ(r.stack_bytes, 26272 + 320);
  EXPECT_FALSE(r.bounded);
  EXPECT_TRUE(has_reason(r, "dynamic stack frame"));
}

TEST(StackAudit, CrossCheckReportsEveryDisagreement) {
  Ci a("a.cpp");
  a.def("f", 32).def("g", 64);
  CallGraph g = graph({a});
  std::vector<SuEntry> su;
  std::string err;
  ASSERT_TRUE(parse_su("a.cpp:1:5:f()\t32\tstatic\na.cpp:1:5:g()\t96\tstatic\n", "a.su", su, err)) << err;
  const std::vector<std::string> d = cross_check(g, su);
  ASSERT_EQ(d.size(), 2u);  // g's 64 only in .ci, 96 only in .su
  EXPECT_NE(d[0].find("64"), std::string::npos);
  EXPECT_NE(d[1].find("96"), std::string::npos);
}

TEST(StackAudit, DiamondTakesTheDeepestBranchOnce) {
  //      A(100)
  //     /      \
  //  B(200)   C(50)
  //     \      /
  //      D(10)
  Ci t("d.cpp");
  t.def("A", 100).def("B", 200).def("C", 50).def("D", 10);
  t.call("A", "B").call("A", "C").call("B", "D").call("C", "D");
  const TaskResult r = run(graph({t}), "A");
  EXPECT_TRUE(r.bounded);
  EXPECT_EQ(r.stack_bytes, 310);  // not 370 (both branches) and not 320 (D twice)
  EXPECT_EQ(path_ids(r), (std::vector<std::string>{"A", "B", "D"}));
  EXPECT_EQ(r.functions_reached, 4);
}

TEST(StackAudit, CutEdgesAreNotFollowed) {
  Ci t("c.cpp");
  t.def("tick", 100).def("ekf", 5000).def("mech", 300).call("tick", "ekf").call("tick", "mech");
  const CallGraph g = graph({t});
  EXPECT_EQ(run(g, "tick").stack_bytes, 5100);
  const TaskResult r = run(g, "tick", {"ekf"});
  EXPECT_EQ(r.stack_bytes, 400);
  EXPECT_EQ(path_ids(r), (std::vector<std::string>{"tick", "mech"}));
}

TEST(StackAudit, BudgetIsChecked) {
  Ci t("b.cpp");
  t.def("f", 1000);
  const CallGraph g = graph({t});
  EXPECT_TRUE(run(g, "f", {}, 0, 1000).within_budget);
  EXPECT_FALSE(run(g, "f", {}, 0, 999).within_budget);
  EXPECT_TRUE(run(g, "f", {}, 0, 0).within_budget);  // no budget
}

TEST(StackAudit, RecursionMakesTheBoundUnknown) {
  Ci t("r.cpp");
  t.def("root", 10).def("a", 20).def("b", 30).def("self", 40).def("ok", 5);
  t.call("root", "a").call("a", "b").call("b", "a").call("root", "self").call("self", "self").call("root", "ok");
  const CallGraph g = graph({t});
  const TaskResult r = run(g, "root");
  EXPECT_FALSE(r.bounded);
  EXPECT_TRUE(has_reason(r, "recursion: a -> b -> a"));
  EXPECT_TRUE(has_reason(r, "recursion: self -> self"));
  EXPECT_EQ(r.stack_bytes, 60);  // each cycle counted once: root + a + b
  EXPECT_TRUE(run(g, "ok").bounded);
  // A function reached only through the cycle's members carries the finding too.
  EXPECT_FALSE(run(g, "b").bounded);
}

TEST(StackAudit, IndirectCallMakesTheBoundUnknown) {
  Ci t("i.cpp");
  t.def("f", 16).decl(kIndirectCall).call("f", kIndirectCall);
  const TaskResult r = run(graph({t}), "f");
  EXPECT_FALSE(r.bounded);
  EXPECT_TRUE(has_reason(r, "indirect call"));
  EXPECT_TRUE(r.within_budget);  // no budget given: only boundedness fails
}

TEST(StackAudit, DynamicFramesMakeTheBoundUnknown) {
  for (const char* kind : {"dynamic", "dynamic,bounded"}) {
    Ci t("v.cpp");
    t.def("top", 8).def("vla", 64, kind).call("top", "vla");
    const TaskResult r = run(graph({t}), "top", {}, 0, 1 << 20);
    EXPECT_FALSE(r.bounded) << kind;
    EXPECT_FALSE(r.within_budget) << kind;  // unbounded never passes a budget
    EXPECT_TRUE(has_reason(r, std::string(kind) + " stack frame")) << kind;
    EXPECT_EQ(r.stack_bytes, 72) << kind;
    ASSERT_EQ(r.findings.size(), 1u);
    EXPECT_EQ(r.findings[0].via, (std::vector<std::string>{"top", "vla"}));
  }
}

TEST(StackAudit, HeapCallsMakeTheBoundUnknown) {
  Ci t("h.cpp");
  t.def("f", 8).def("g", 8).decl("malloc").decl("_Znwm").call("f", "malloc").call("g", "_Znwm");
  const CallGraph g = graph({t});
  EXPECT_TRUE(has_reason(run(g, "f"), "heap call malloc"));
  EXPECT_TRUE(has_reason(run(g, "g"), "heap call _Znwm"));
}

TEST(StackAudit, LibraryFunctionsTakeTheirAssumedCostOrAreUnknown) {
  Ci t("l.cpp");
  t.def("f", 100).def("g", 100).decl("sin").decl("mystery").call("f", "sin").call("g", "mystery");
  const CallGraph g = graph({t});
  long sin_cost = -1;
  for (const ExternalCost& c : external_costs())
    if (c.name == "sin") sin_cost = c.bytes;
  ASSERT_GT(sin_cost, 0);
  const TaskResult f = run(g, "f");
  EXPECT_TRUE(f.bounded);
  EXPECT_EQ(f.stack_bytes, 100 + sin_cost);
  EXPECT_EQ(f.assumed_externals, (std::vector<std::string>{"sin (" + std::to_string(sin_cost) + " B)"}));
  const TaskResult u = run(g, "g");
  EXPECT_FALSE(u.bounded);
  EXPECT_TRUE(has_reason(u, "no stack information for mystery"));
}

TEST(StackAudit, ComdatDefinitionsLinkAcrossUnitsAndTheWorstCopyCounts) {
  // GCC titles the functions a TU emits as COMDAT "<file>:<symbol>"; callers elsewhere say "<symbol>".
  Ci a("a.cpp"), b("b.cpp"), c("c.cpp");
  a.def("a.cpp:_Z4tickv", 100).decl("_Z6updatev").call("a.cpp:_Z4tickv", "_Z6updatev");
  b.def("b.cpp:_Z6updatev", 3000);
  c.def("c.cpp:_Z6updatev", 3200);  // the same inline function emitted by a second TU
  const CallGraph g = graph({a, b, c});
  EXPECT_TRUE(g.functions.at("_Z6updatev").linked);
  const TaskResult r = run(g, "a.cpp:_Z4tickv");
  EXPECT_TRUE(r.bounded);
  EXPECT_EQ(r.stack_bytes, 3300);
  EXPECT_EQ(path_ids(r), (std::vector<std::string>{"a.cpp:_Z4tickv", "c.cpp:_Z6updatev"}));  // reference hidden
  // Cutting the reference cuts its definitions.
  EXPECT_EQ(run(g, "a.cpp:_Z4tickv", {"_Z6updatev"}).stack_bytes, 100);
  // A task may be rooted at the reference (as the entry wrappers resolve it).
  EXPECT_EQ(run(g, "_Z6updatev").stack_bytes, 3200);
}

TEST(StackAudit, RedZoneIsAddedToLeavesOnly) {
  Ci t("z.cpp");
  t.def("outer", 64).def("leaf", 32).decl("sqrt").def("calls_lib", 16).call("outer", "leaf").call("calls_lib", "sqrt");
  const CallGraph g = graph({t});
  EXPECT_EQ(run(g, "outer", {}, 128).stack_bytes, 64 + 32 + 128);
  long sqrt_cost = 0;
  for (const ExternalCost& c : external_costs())
    if (c.name == "sqrt") sqrt_cost = c.bytes;
  EXPECT_EQ(run(g, "calls_lib", {}, 128).stack_bytes, 16 + sqrt_cost);  // not a leaf: it calls sqrt
}

TEST(StackAudit, SingleCalleeResolvesEntryWrappers) {
  Ci t("w.cpp");
  t.def("wrap_ok", 8).def("wrap_two", 8).decl("_Z1fv").decl("_Z1gv");
  t.call("wrap_ok", "_Z1fv").call("wrap_two", "_Z1fv").call("wrap_two", "_Z1gv");
  const CallGraph g = graph({t});
  EXPECT_EQ(single_callee(g, "wrap_ok"), "_Z1fv");
  EXPECT_THROW(single_callee(g, "wrap_two"), std::runtime_error);
  EXPECT_THROW(single_callee(g, "missing"), std::runtime_error);
  EXPECT_THROW(run(g, "missing"), std::runtime_error);
}

TEST(StackAudit, MalformedInputIsRejectedWithItsLine) {
  CallGraph g;
  std::string err;
  EXPECT_FALSE(parse_ci("graph: { title: \"x\"\nnode: { title: \"f\" label: \"f\\nx:1:1\\nlots of bytes\" }\n}\n", "x.ci", g,
                        err));
  EXPECT_NE(err.find("x.ci:"), std::string::npos) << err;
  EXPECT_NE(err.find("unrecognised stack usage"), std::string::npos) << err;
  EXPECT_TRUE(g.functions.empty());  // nothing merged from a failed file
  EXPECT_FALSE(parse_ci("graph: { title: \"x\"\nnode: { title: \"f\" label: \"f\" }\n", "y.ci", g, err));
  EXPECT_NE(err.find("not closed"), std::string::npos) << err;
  EXPECT_FALSE(parse_ci("digraph {}", "z.ci", g, err));
  EXPECT_FALSE(parse_ci("graph: { title: \"x\"\nedge: { sourcename: \"a\" }\n}\n", "e.ci", g, err));
  std::vector<SuEntry> su;
  EXPECT_FALSE(parse_su("ok.cpp:1:1:f()\t8\tstatic\nbroken line\n", "b.su", su, err));
  EXPECT_NE(err.find("b.su:2:"), std::string::npos) << err;
  EXPECT_TRUE(su.empty());
  EXPECT_FALSE(parse_su("a.cpp:1:1:f()\t8\tweird\n", "k.su", su, err));
  EXPECT_FALSE(parse_su("a.cpp:1:f()\t8\tstatic\n", "c.su", su, err));                     // no column
  EXPECT_FALSE(parse_su("a.cpp:1:1:f()\t99999999999999999999\tstatic\n", "o.su", su, err));  // absurd size
  EXPECT_FALSE(parse_su("a.cpp:1:1:f()\t-8\tstatic\n", "n.su", su, err));
  EXPECT_TRUE(su.empty());
  ASSERT_TRUE(parse_su("C:/w/a b.cpp:12:3:ns::f(int) const [with T = a:b]\t16\tdynamic,bounded\n", "w.su", su, err))
      << err;
  EXPECT_EQ(su[0].location, "C:/w/a b.cpp:12:3");
  EXPECT_EQ(su[0].function, "ns::f(int) const [with T = a:b]");
  EXPECT_EQ(su[0].kind, FrameKind::kDynamicBounded);
}

TEST(StackAudit, CompactNameDropsParametersAndNotes) {
  EXPECT_EQ(compact_name("fsw::Ekf<L>::update(fsw::GnssEpoch const&, double (*)(int)) const [ekf.cpp]"), "fsw::Ekf<L>::update");
  EXPECT_EQ(compact_name("Eigen::run(long) [clone .constprop.0] [ekf.cpp]"), "Eigen::run");
  EXPECT_EQ(compact_name("sincos"), "sincos");
  EXPECT_EQ(compact_name("fsw::Executive<fsw::X<(fsw::Block)0> >::tick(fsw::FrameInput const&)"),
            "fsw::Executive<fsw::X<(fsw::Block)0> >::tick");
}

// ---- The assumed library costs against a measurement ---------------------------------------------

using Probe = void (*)(double);
Probe g_probe = nullptr;
double g_arg = 0.0;
std::uintptr_t g_mark = 0;

__attribute__((noinline)) void call_probe() {
  volatile char marker = 0;
  g_mark = reinterpret_cast<std::uintptr_t>(&marker);
  g_probe(g_arg);
  (void)marker;
}
void* probe_thread(void*) {
  call_probe();
  return nullptr;
}

/// Deepest stack use below the caller's frame of one call of fn(x), on a thread whose stack is
/// painted with a pattern beforehand (the probe's own small wrapper frame included).
long measured_stack_bytes(Probe fn, double x) {
  constexpr std::size_t kSize = 1 << 18;
  static std::vector<unsigned char> mem(kSize + 2 * 4096);
  const std::uintptr_t base = (reinterpret_cast<std::uintptr_t>(mem.data()) + 4095) & ~std::uintptr_t{4095};
  unsigned char* stack = reinterpret_cast<unsigned char*>(base);
  std::memset(stack, 0xA5, kSize);
  g_probe = fn;
  g_arg = x;
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstack(&attr, stack, kSize);
  pthread_t t;
  EXPECT_EQ(pthread_create(&t, &attr, probe_thread, nullptr), 0);
  pthread_join(t, nullptr);
  pthread_attr_destroy(&attr);
  std::size_t untouched = 0;
  while (untouched < kSize && stack[untouched] == 0xA5) ++untouched;
  return static_cast<long>(g_mark - (base + untouched));
}

volatile double g_sink = 0.0;
unsigned char g_buf_a[4096], g_buf_b[4096];

struct Library {
  const char* name;
  Probe probe;
};
const Library kLibrary[] = {
    {"sin", [](double x) { g_sink = std::sin(x); }},
    {"cos", [](double x) { g_sink = std::cos(x); }},
    {"tan", [](double x) { g_sink = std::tan(x); }},
    {"sincos", [](double x) { double s = 0.0, c = 0.0; ::sincos(x, &s, &c); g_sink = s + c; }},
    {"exp", [](double x) { g_sink = std::exp(x); }},
    {"log", [](double x) { g_sink = std::log(x); }},
    {"sqrt", [](double x) { g_sink = std::sqrt(x); }},
    {"atan", [](double x) { g_sink = std::atan(x); }},
    {"atan2", [](double x) { g_sink = std::atan2(x, 0.7) + std::atan2(0.3, x); }},
    {"asin", [](double x) { g_sink = std::asin(x); }},
    {"acos", [](double x) { g_sink = std::acos(x); }},
    {"pow", [](double x) { g_sink = std::pow(x, 1.3) + std::pow(1.3, x); }},
    {"hypot", [](double x) { g_sink = std::hypot(x, 2.0); }},
    {"fmod", [](double x) { g_sink = std::fmod(x, 2.0); }},
    {"lround", [](double x) { g_sink = static_cast<double>(std::lround(x)); }},
    {"memset", [](double x) { std::memset(g_buf_a, static_cast<int>(x) & 0xff, sizeof g_buf_a); }},
    {"memcpy", [](double x) { std::memcpy(g_buf_b, g_buf_a, sizeof g_buf_b); g_sink = g_buf_b[7] + x; }},
    {"memmove", [](double x) { std::memmove(g_buf_a + 1, g_buf_a, 4000); g_sink = g_buf_a[9] + x; }},
    {"memcmp", [](double x) { g_sink = std::memcmp(g_buf_a, g_buf_b, sizeof g_buf_a) + x; }},
};

TEST(StackAudit, LibraryCostsBoundMeasuredUse) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer replaces mem* and adds red zones to the probes: the table describes plain builds";
#endif
  // Ordinary, tiny, huge (slow argument reduction), overflowing, infinite and NaN arguments.
  const double args[] = {0.0, 1e-300, 5e-324, 0.5, 1.0, 3.0, 100.0, 1e6, 1e22, 1e300, -1e300, 0x1p1000, 710.0, -745.0,
                         INFINITY, -INFINITY, NAN};
  const long nop = [] {
    long m = 0;
    for (int i = 0; i < 3; ++i) m = std::max(m, measured_stack_bytes([](double) {}, 0.0));
    return m;
  }();
  EXPECT_GT(nop, 0);  // the paint and the marker work
  int checked = 0;
  for (const Library& lib : kLibrary) {
    long assumed = -1;
    for (const ExternalCost& c : external_costs())
      if (c.name == lib.name) assumed = c.bytes;
    ASSERT_GT(assumed, 0) << lib.name << " has no assumed cost";
    for (double x : args) lib.probe(x);  // bind the PLT entry first (lazy binding costs ~3 KiB once)
    long worst = 0;
    for (double x : args) worst = std::max(worst, measured_stack_bytes(lib.probe, x));
    EXPECT_LE(worst, assumed) << lib.name << ": measured " << worst << " B (probe wrapper alone " << nop << " B)";
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(sizeof kLibrary / sizeof kLibrary[0]));
  // The measurement sees a real frame: a probe with a 2 KiB local array must measure >= 2 KiB.
  const long big = measured_stack_bytes(
      [](double x) {
        volatile char buf[2048];
        for (int i = 0; i < 2048; i += 64) buf[i] = static_cast<char>(x);
        g_sink = buf[1024];
      },
      1.0);
  EXPECT_GE(big, 2048);
}

}  // namespace
