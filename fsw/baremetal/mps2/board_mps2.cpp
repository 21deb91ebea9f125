// Board port for QEMU's mps2-an500 (Cortex-M7; docs/baremetal-qemu.md): ARM semihosting (BKPT
// 0xAB; QEMU: -semihosting-config enable=on,target=native) for the input file, the output file and
// the exit status; the SysTick counter on the processor clock for instruction counts under
// QEMU -icount; then the target replay (../replay.cpp), the same source the host tool runs.
//
// Command line (SYS_GET_CMDLINE, QEMU's semihosting arg=... values): NAME INPUT OUTPUT [dwt|libm]
// "libm" runs the libm probe (replay.hpp) instead of the replay (INPUT is not read). "dwt" first
// probes the DWT cycle counter (DEMCR.TRCENA, DWT_CTRL.CYCCNTENA, two CYCCNT reads) and reports what
// QEMU models. The output starts with a "C" line: MVFR0 MVFR1 MVFR2 CPACR (hex),
// then the SysTick calibration: instructions of a counted loop and the SysTick ticks it took; it
// ends with "STACK used reserved" (the high-water mark of the main stack, painted at start) and
// "END result write_error".
#include <cstddef>
#include <cstdint>

#include "../replay.hpp"

extern "C" {
void sdins_board_fault(std::uint32_t ipsr) __attribute__((noreturn));
void sdins_board_exit(int code) __attribute__((noreturn));
}

namespace {

// ---- semihosting (ARM "Semihosting for AArch32 and AArch64", version 2) ----
enum : std::uint32_t {
  kSysOpen = 0x01,
  kSysClose = 0x02,
  kSysWrite0 = 0x04,
  kSysWrite = 0x05,
  kSysRead = 0x06,
  kSysGetCmdline = 0x15,
  kSysExitExtended = 0x20,
  kAdpStoppedApplicationExit = 0x20026,
};

std::uint32_t semihost(std::uint32_t op, const void* arg) {
  register std::uint32_t r0 __asm__("r0") = op;
  register const void* r1 __asm__("r1") = arg;
  __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

void write0(const char* s) { semihost(kSysWrite0, s); }

std::size_t length(const char* s) {
  std::size_t n = 0;
  while (s[n] != '\0') ++n;
  return n;
}

/// SYS_OPEN mode: 1 "rb", 5 "wb". Returns the handle or -1.
int open_file(const char* path, std::uint32_t mode) {
  const std::uint32_t args[3] = {reinterpret_cast<std::uint32_t>(path), mode, static_cast<std::uint32_t>(length(path))};
  return static_cast<int>(semihost(kSysOpen, args));
}

// ---- buffered input and output ----
int g_in = -1, g_out = -1;
unsigned char g_in_buf[16384];
std::size_t g_in_pos = 0, g_in_len = 0;
bool g_in_eof = false;
char g_out_buf[16384];
std::size_t g_out_len = 0;
bool g_out_error = false;

void flush_out() {
  if (g_out_len == 0) return;
  const std::uint32_t args[3] = {static_cast<std::uint32_t>(g_out), reinterpret_cast<std::uint32_t>(g_out_buf),
                                 static_cast<std::uint32_t>(g_out_len)};
  if (semihost(kSysWrite, args) != 0u) g_out_error = true;  // returns the bytes NOT written
  g_out_len = 0;
}

void board_write(const char* s, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (g_out_len == sizeof g_out_buf) flush_out();
    g_out_buf[g_out_len++] = s[i];
  }
}

std::size_t board_read(void* dst, std::size_t n) {
  auto* d = static_cast<unsigned char*>(dst);
  std::size_t done = 0;
  while (done < n) {
    if (g_in_pos == g_in_len) {
      if (g_in_eof) return done;
      const std::uint32_t args[3] = {static_cast<std::uint32_t>(g_in), reinterpret_cast<std::uint32_t>(g_in_buf),
                                     static_cast<std::uint32_t>(sizeof g_in_buf)};
      const std::uint32_t not_read = semihost(kSysRead, args);
      if (not_read > sizeof g_in_buf) return done;  // -1: error
      g_in_len = sizeof g_in_buf - not_read;
      g_in_pos = 0;
      if (g_in_len < sizeof g_in_buf) g_in_eof = true;
      if (g_in_len == 0) return done;
    }
    d[done++] = g_in_buf[g_in_pos++];
  }
  return done;
}

// ---- Cortex-M system registers ----
volatile std::uint32_t& reg(std::uint32_t addr) { return *reinterpret_cast<volatile std::uint32_t*>(addr); }
constexpr std::uint32_t kSystCsr = 0xE000E010, kSystRvr = 0xE000E014, kSystCvr = 0xE000E018;
constexpr std::uint32_t kCpacr = 0xE000ED88, kMvfr0 = 0xE000EF40, kMvfr1 = 0xE000EF44, kMvfr2 = 0xE000EF48;
constexpr std::uint32_t kCfsr = 0xE000ED28, kHfsr = 0xE000ED2C, kBfar = 0xE000ED38;
constexpr std::uint32_t kDemcr = 0xE000EDFC, kDwtCtrl = 0xE0001000, kDwtCyccnt = 0xE0001004;

std::uint32_t systick() { return reg(kSystCvr); }

void start_systick() {
  reg(kSystRvr) = 0x00FFFFFFu;  // 24-bit down-counter, free running
  reg(kSystCvr) = 0u;
  reg(kSystCsr) = 0x5u;         // ENABLE, CLKSOURCE = processor clock, no interrupt
}

/// 2 * n + 1 instructions (mov, then n times subs + bne).
__attribute__((noinline, naked)) void counted_loop(std::uint32_t /*n, in r0*/) {
  __asm__ volatile(
      "mov r1, r0\n"
      "1: subs r1, r1, #1\n"
      "bne 1b\n"
      "bx lr\n");
}

// ---- output helpers for the board's own lines ----
void hex32(char* p, std::uint32_t v) {
  for (int k = 7; k >= 0; --k) *p++ = "0123456789abcdef"[(v >> (4 * k)) & 0xFu];
}
std::size_t dec32(char* p, std::uint32_t v) {
  char tmp[10];
  std::size_t k = 0;
  do {
    tmp[k++] = static_cast<char>('0' + v % 10u);
    v /= 10u;
  } while (v != 0u);
  for (std::size_t i = 0; i < k; ++i) p[i] = tmp[k - 1 - i];
  return k;
}

void emit_words(const char* tag, const std::uint32_t* hex, int n_hex, const std::uint32_t* dec, int n_dec,
                bool to_console) {
  char line[160];
  std::size_t n = 0;
  for (const char* t = tag; *t != '\0';) line[n++] = *t++;
  for (int i = 0; i < n_hex; ++i) {
    line[n++] = ' ';
    hex32(line + n, hex[i]);
    n += 8;
  }
  for (int i = 0; i < n_dec; ++i) {
    line[n++] = ' ';
    n += dec32(line + n, dec[i]);
  }
  line[n++] = '\n';
  line[n] = '\0';
  if (to_console) write0(line);
  if (g_out >= 0) board_write(line, n);
}

/// Splits the semihosting command line in place; returns the number of words.
int split(char* s, char** words, int max_words) {
  int n = 0;
  while (*s != '\0' && n < max_words) {
    while (*s == ' ') *s++ = '\0';
    if (*s == '\0') break;
    words[n++] = s;
    while (*s != '\0' && *s != ' ') ++s;
  }
  return n;
}

char g_cmdline[512];

// Stack high-water mark: the free part of the stack is painted at start; the deepest word that no
// longer holds the paint at the end is the most the run used.
extern "C" std::uint32_t _sstack[], _estack[];
constexpr std::uint32_t kStackPaint = 0x5A5A5A5Au;

__attribute__((noinline)) void paint_stack() {
  std::uint32_t here = 0;
  auto* top = reinterpret_cast<std::uint32_t*>(reinterpret_cast<std::uintptr_t>(&here) & ~std::uintptr_t{7}) - 64;
  for (std::uint32_t* w = _sstack; w < top; ++w) *w = kStackPaint;
}

std::uint32_t stack_used_bytes() {
  const std::uint32_t* w = _sstack;
  while (w < _estack && *w == kStackPaint) ++w;
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(_estack) - reinterpret_cast<std::uintptr_t>(w));
}

}  // namespace

extern "C" void sdins_board_exit(int code) {
  const std::uint32_t args[2] = {kAdpStoppedApplicationExit, static_cast<std::uint32_t>(code)};
  semihost(kSysExitExtended, args);
  for (;;) {
  }
}

extern "C" void sdins_board_fault(std::uint32_t ipsr) {
  const std::uint32_t regs[4] = {ipsr, reg(kCfsr), reg(kHfsr), reg(kBfar)};
  emit_words("FAULT ipsr cfsr hfsr bfar", regs, 4, nullptr, 0, true);
  if (g_out >= 0) flush_out();
  sdins_board_exit(70);
}

int main() {
  paint_stack();
  const std::uint32_t cl_args[2] = {reinterpret_cast<std::uint32_t>(g_cmdline), sizeof g_cmdline - 1};
  char* words[6] = {};
  const int n_words = semihost(kSysGetCmdline, cl_args) == 0u ? split(g_cmdline, words, 6) : 0;
  if (n_words < 3) {
    write0("sdins_fsw_mps2: usage (semihosting arguments): NAME INPUT OUTPUT [dwt|libm]\n");
    return 64;
  }
  const bool libm_probe = n_words >= 4 && words[3][0] == 'l';
  g_in = libm_probe ? 0 : open_file(words[1], 1);
  g_out = open_file(words[2], 5);
  if (g_in < 0 || g_out < 0) {
    write0("sdins_fsw_mps2: cannot open the input or the output file\n");
    return 66;
  }
  start_systick();
  const std::uint32_t fpu[4] = {reg(kMvfr0), reg(kMvfr1), reg(kMvfr2), reg(kCpacr)};
  constexpr std::uint32_t kLoop = 100000u;
  const std::uint32_t t0 = systick();
  counted_loop(kLoop);
  const std::uint32_t t1 = systick();
  const std::uint32_t calib[2] = {2u * kLoop + 1u, (t0 - t1) & 0x00FFFFFFu};
  emit_words("C", fpu, 4, calib, 2, true);
  if (n_words >= 4 && words[3][0] == 'd') {
    reg(kDemcr) = reg(kDemcr) | (1u << 24);  // TRCENA
    reg(kDwtCtrl) = reg(kDwtCtrl) | 1u;      // CYCCNTENA
    const std::uint32_t c0 = reg(kDwtCyccnt);
    counted_loop(kLoop);
    const std::uint32_t c1 = reg(kDwtCyccnt);
    const std::uint32_t dwt[3] = {reg(kDwtCtrl), c0, c1};
    emit_words("DWT ctrl cyccnt0 cyccnt1", dwt, 3, nullptr, 0, true);
  }
  const sdins_target::Board board{board_read, board_write, systick, 0x00FFFFFFu};
  if (libm_probe) {
    sdins_target::run_libm_probe(board);
    flush_out();
    const std::uint32_t close_probe = static_cast<std::uint32_t>(g_out);
    semihost(kSysClose, &close_probe);
    return g_out_error ? 10 : 0;
  }
  const sdins_target::ReplayResult r = sdins_target::run_replay(board);
  flush_out();
  const std::uint32_t stack[2] = {stack_used_bytes(),
                                  static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(_estack) -
                                                             reinterpret_cast<std::uintptr_t>(_sstack))};
  emit_words("STACK used reserved", nullptr, 0, stack, 2, true);
  const std::uint32_t end[2] = {static_cast<std::uint32_t>(r), g_out_error ? 1u : 0u};
  emit_words("END result write_error", nullptr, 0, end, 2, true);
  flush_out();
  const std::uint32_t close_out = static_cast<std::uint32_t>(g_out);
  semihost(kSysClose, &close_out);
  return r == sdins_target::ReplayResult::kOk && !g_out_error ? 0 : static_cast<int>(r) + (g_out_error ? 10 : 0);
}
