#include "rgbdtam/core/assert.hpp"

#include <cstdio>
#include <cstdlib>

namespace rgbdtam {
namespace {
void abort_handler(const char* expr, const char* msg, const char* file, int line) {
  std::fprintf(stderr, "rgbdtam: assertion failed: %s (%s) at %s:%d\n", expr, msg, file, line);
}
AssertHandler g_handler = abort_handler;
}  // namespace

AssertHandler set_assert_handler(AssertHandler handler) {
  AssertHandler previous = g_handler;
  g_handler = handler != nullptr ? handler : abort_handler;
  return previous;
}

void assert_failed(const char* expr, const char* msg, const char* file, int line) {
  g_handler(expr, msg, file, line);
  std::abort();  // A handler may log, but a broken invariant never continues.
}

}  // namespace rgbdtam
