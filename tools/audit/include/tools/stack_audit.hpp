// Worst-case stack depth from GCC's per-function stack usage and call graph.
//
// Inputs, written by GCC for every translation unit compiled with
//   -fstack-usage              <tu>.su: "file:line:col:function<TAB>bytes<TAB>qualifier"
//   -fcallgraph-info=su        <tu>.ci: the TU's call graph in VCG, one node per function with its
//                              stack usage in the label ("N bytes (static)") for the functions the
//                              TU defines, one edge per call site.
// Node titles are assembler names (mangled; file-local symbols are prefixed with "<file>:"), so
// the graphs of all TUs merge by title: a function defined in one TU and called from another is
// one node. Functions defined in several TUs (inline, templates) keep the largest frame.
//
// The stack usage comes from the .ci labels; the .su files are read as an independent record of
// the same numbers and every (location, bytes, qualifier) must appear in both (cross_check()), so
// a parsing slip on either side cannot go unnoticed.
//
// worst(f) = frame(f) + max over the callees c of f of worst(c). The bound is UNKNOWN
// (TaskResult::bounded = false) as soon as a reachable function
//   - has a dynamic frame (alloca, variable-length array: qualifier "dynamic" or "dynamic,bounded"),
//   - is part of a recursion (a cycle of the call graph),
//   - makes an indirect call (function pointer, virtual call: GCC's "__indirect_call" node),
//   - calls the heap (malloc/free/operator new ...), or
//   - calls a function for which there is no stack information and no assumed cost.
// stack_bytes is then still reported (recursion counted once, dynamic frames with their static
// part, unknown callees as 0), as a lower bound. Functions from libraries that are not compiled
// here (libm, libc's mem* routines) take the assumed costs of external_costs(); each use is listed.
#pragma once

#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace tools::stack {

enum class FrameKind { kStatic, kDynamic, kDynamicBounded };
const char* to_string(FrameKind k);

/// One function of the merged call graph.
struct Function {
  std::string id;            ///< node title: assembler name, "<file>:<name>" for file-local symbols
  std::string label;         ///< first line of the node label (GCC's printable name)
  std::string location;      ///< "file:line:col" of the definition (or declaration)
  bool defined = false;      ///< a compiled TU defines it: frame_bytes and kind are known
  long frame_bytes = 0;
  FrameKind kind = FrameKind::kStatic;
  std::set<std::string> callees;
  /// A reference resolved by link(): its callees are the definitions of the same symbol in the
  /// TUs that define it (COMDAT copies); it has no frame of its own.
  bool linked = false;
};

struct CallGraph {
  std::map<std::string, Function> functions;
  /// Every stack-usage record of the .ci files as "location bytes kind", one per defining TU
  /// (a function that several TUs define appears once per TU, as in the .su files).
  std::vector<std::string> frame_records;
  int units = 0;  ///< .ci files merged
};

/// Parses one .ci text and merges it into g. Returns false with err = "<source>:<line>: reason"
/// for text that is not GCC's VCG call graph.
bool parse_ci(const std::string& text, const std::string& source, CallGraph& g, std::string& err);

struct SuEntry {
  std::string location;  ///< "file:line:col"
  std::string function;  ///< GCC's printable name
  long bytes = 0;
  FrameKind kind = FrameKind::kStatic;
};

/// Resolves references across TUs. GCC titles the functions a TU emits as COMDAT (inline functions,
/// template instantiations, explicit ones included) and its file-local ones "<file>:<symbol>";
/// another TU that calls the same function names it "<symbol>". Every undefined "<symbol>" for
/// which some TU defines "<file>:<symbol>" becomes a linked node whose callees are those
/// definitions (the worst copy counts). Call after the last parse_ci(); idempotent.
void link(CallGraph& g);

/// Parses one .su text (appends to out). Returns false with err on a malformed line.
bool parse_su(const std::string& text, const std::string& source, std::vector<SuEntry>& out, std::string& err);

/// Differences between the stack-usage records of the .su files and those of the .ci files, compared
/// as multisets of (location, bytes, kind). Empty: both agree.
std::vector<std::string> cross_check(const CallGraph& g, const std::vector<SuEntry>& su);

/// Assumed stack cost of a function for which no .su information exists (a library function).
struct ExternalCost {
  std::string name;
  long bytes = 0;
  std::string basis;  ///< where the number comes from
};

/// The table used by the audit (host x86-64, glibc). See the definition for the basis of each.
const std::vector<ExternalCost>& external_costs();

/// Heap entry points (C and C++): calling one makes a task unbounded and is reported as heap use.
bool is_heap_function(const std::string& id);

/// GCC's placeholder node for calls through a pointer.
inline constexpr const char* kIndirectCall = "__indirect_call";

struct TaskSpec {
  std::string name;
  std::string root;               ///< function id
  std::set<std::string> cut;      ///< callees not followed (work that runs in another task)
  long budget_bytes = 0;          ///< 0: no budget
  std::string description;
  /// Stack a function that calls nothing may use below its stack pointer without it appearing in
  /// its .su frame: the x86-64 System V red zone (128 bytes); 0 on ARM. Added to every leaf.
  long red_zone_bytes = 0;
};

struct PathStep {
  std::string id;
  std::string name;  ///< demangled
  long frame_bytes = 0;
  std::string note;  ///< "dynamic", "assumed (libm)", "no stack information", ...
};

/// Why a bound is unknown, with the call chain from the task's root that first reached it (ids).
struct Finding {
  std::string reason;
  std::vector<std::string> via;
};

struct TaskResult {
  std::string name;
  std::string root;
  std::string description;
  long stack_bytes = 0;
  bool bounded = true;
  long budget_bytes = 0;
  bool within_budget = true;   ///< bounded and stack_bytes <= budget (true when there is no budget)
  std::vector<PathStep> path;  ///< the deepest call path, root first
  std::vector<std::string> unbounded_reasons;
  std::vector<Finding> findings;  ///< the same reasons, each with a call chain that reaches it
  std::vector<std::string> assumed_externals;  ///< "name (N bytes)" for every external cost used
  int functions_reached = 0;
};

/// The worst-case stack depth of spec.root over g. An unknown root is an error (std::runtime_error).
TaskResult analyse(const CallGraph& g, const TaskSpec& spec, const std::vector<ExternalCost>& costs);

/// The single callee of function `wrapper` (an entry-point wrapper that only forwards a call).
/// Throws std::runtime_error if the wrapper is missing or does not have exactly one callee.
std::string single_callee(const CallGraph& g, const std::string& wrapper);

/// Everything the stack-audit build wrote: the merged call graph of all .ci files and the records
/// of all .su files found (recursively) under a build directory.
struct BuildData {
  CallGraph graph;
  std::vector<SuEntry> su;
  int ci_files = 0;
  int su_files = 0;
};
/// Throws std::runtime_error on unreadable or malformed files, or when there are none.
BuildData load_build_dir(const std::string& dir);

/// The x86-64 System V red zone.
inline constexpr long kX86_64RedZoneBytes = 128;

// ---- The fsw tasks ------------------------------------------------------------------------------

/// The four layouts of fsw/include/fsw/error_state.hpp, as named by fsw/audit/stack_entries.cpp.
const std::vector<std::string>& fsw_layouts();

/// The budgeted tasks, per layout:
///   mech_200hz/<L>: Executive<L>::tick without the 1 Hz group (Ekf::propagate, update and
///                   feedback cut): IMU compensation, frame builder, strapdown step, Ekf::accumulate,
///                   and run_ekf's own frame (it runs every frame once the EKF is due, even when it
///                   only waits for the GNSS epoch);
///   ekf_1hz/<L>:    Executive<L>::tick of the minor frame that runs the 1 Hz group (everything).
/// and the unbudgeted component functions (Ekf::accumulate/propagate/update/feedback per layout,
/// Strapdown::step, FrameBuilder::add) in `functions`. Roots are resolved through the entry
/// wrappers (single_callee); throws std::runtime_error when one is missing.
void fsw_task_specs(const CallGraph& g, long budget_bytes, long red_zone_bytes, std::vector<TaskSpec>& tasks,
                    std::vector<TaskSpec>& functions);

/// One self-check of the instrument on tests/stack/stack_fixtures.cpp.
struct SelfCheck {
  std::string fixture;
  std::string expect;
  bool pass = false;
  std::string detail;
};
/// Analyses the fixtures of the stack-audit build and compares with what they are built to show.
std::vector<SelfCheck> self_check(const CallGraph& g, const std::vector<ExternalCost>& costs, long red_zone_bytes);

/// Readable name of a function id: demangled, "<name> [<file name>]" for "<file>:<symbol>" ids.
std::string demangle(const std::string& id);

/// A demangled function name without its parameter list, qualifiers and bracketed notes
/// ("fsw::Ekf<L>::update(GnssEpoch const&, ...) const [ekf.cpp]" -> "fsw::Ekf<L>::update").
std::string compact_name(const std::string& demangled);

/// The demangled spelling of each fsw layout type (from the entry wrappers) and its alias
/// ("fsw::ErrorStateLayout<(fsw::Block)0, ...>" -> "Layout15"), longest spelling first.
std::vector<std::pair<std::string, std::string>> layout_aliases(const CallGraph& g);
/// s with every layout spelling replaced by its alias.
std::string with_aliases(std::string s, const std::vector<std::pair<std::string, std::string>>& aliases);

}  // namespace tools::stack
