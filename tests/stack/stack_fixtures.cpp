// Self-check fixtures of the stack audit: small functions whose call-graph shape is known, compiled
// with the fsw flags in the stack-audit build (cmake/StackAudit.cmake). `sdins audit stack` analyses
// each one from the real compiler output and refuses to report (exit 1) when the result is not the
// expected one, so the audit cannot silently stop seeing recursion, indirect calls, dynamic
// frames (including the Eigen general-product trap) or calls without stack information.
#include <Eigen/Core>

extern "C" {

int sdins_stack_fixture_undefined(int x);  // declared, defined nowhere: no stack information

// Diamond: root -> {small, big} -> leaf. Worst case: root + big + leaf.
__attribute__((noinline)) int sdins_stack_fixture_leaf(int x) {
  volatile char buf[512];
  buf[x & 511] = static_cast<char>(x);
  return buf[(x * 7) & 511];
}
__attribute__((noinline)) int sdins_stack_fixture_small(int x) {
  volatile char buf[1024];
  buf[x & 1023] = static_cast<char>(x);
  return sdins_stack_fixture_leaf(buf[(x * 3) & 1023]) + 1;
}
__attribute__((noinline)) int sdins_stack_fixture_big(int x) {
  volatile char buf[3072];
  buf[x % 3072] = static_cast<char>(x);
  return sdins_stack_fixture_leaf(buf[(x * 5) % 3072]) + 2;
}
int sdins_stack_fixture_diamond(int x) {
  volatile char buf[64];
  buf[x & 63] = 1;
  return (x > 0 ? sdins_stack_fixture_small(x) : sdins_stack_fixture_big(x)) + buf[(x + 1) & 63];
}

// Recursion: the volatile access after the call keeps it a real (non-tail) call.
int sdins_stack_fixture_recursion(int n) {
  volatile int buf[16];
  buf[0] = n;
  if (n <= 0) return buf[0];
  buf[1] = sdins_stack_fixture_recursion(n - 1);
  return buf[1] + buf[0];
}

// Indirect call.
int sdins_stack_fixture_indirect(int (*fn)(int), int x) { return fn(x) + 1; }

// Dynamic frame.
int sdins_stack_fixture_alloca(int n) {
  volatile char* p = static_cast<volatile char*>(__builtin_alloca(static_cast<unsigned>(n) + 1u));
  p[0] = static_cast<char>(n);
  p[n] = 1;
  return p[0] + p[n];
}

// Call to a function without stack information.
int sdins_stack_fixture_external(int x) { return sdins_stack_fixture_undefined(x) * 2; }

// The known trap: a fixed-size 9x9 product goes through Eigen's general matrix product
// (rows + cols + depth > EIGEN_GEMM_TO_COEFFBASED_THRESHOLD), whose blocking buffers are declared
// with alloca (or malloc for large sizes) in code GCC compiles for every size.
void sdins_stack_fixture_eigen_product(const Eigen::Matrix<double, 9, 9>& a, const Eigen::Matrix<double, 9, 9>& b,
                                       Eigen::Matrix<double, 9, 9>& c) {
  c.noalias() = a * b;
}

}  // extern "C"
