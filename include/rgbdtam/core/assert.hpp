#pragma once
// Programmer errors: one handler for the whole program, chosen by the application.
// Recoverable errors are returned as Status values instead (status.hpp).

namespace rgbdtam {

using AssertHandler = void (*)(const char* expr, const char* msg, const char* file, int line);

// The default handler prints and aborts. Returns the previous handler.
AssertHandler set_assert_handler(AssertHandler handler);
[[noreturn]] void assert_failed(const char* expr, const char* msg, const char* file, int line);

}  // namespace rgbdtam

#define RGBDTAM_ASSERT(expr, msg)                                            \
  do {                                                                       \
    if (!(expr)) ::rgbdtam::assert_failed(#expr, (msg), __FILE__, __LINE__); \
  } while (0)
