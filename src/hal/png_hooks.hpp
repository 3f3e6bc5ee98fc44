#pragma once
// libpng's allocation and error hooks, shared by the PNG decoder and encoder (hal-private).

#include <png.h>

#include <cstdio>

#include "rgbdtam/hal/png_arena.hpp"

namespace rgbdtam::png_hooks {

// The png struct's mem_ptr must be the PngArena.
inline png_voidp arena_malloc(png_structp png, png_alloc_size_t n) {
  return static_cast<PngArena*>(png_get_mem_ptr(png))->alloc(n);
}
inline void arena_free(png_structp, png_voidp) {}  // PngArena::reset() frees all at once

// The png struct's error_ptr must be an ErrorSink: the message is kept and control returns
// to the setjmp point.
struct ErrorSink {
  char message[160];
};
inline void on_error(png_structp png, png_const_charp msg) {
  auto* sink = static_cast<ErrorSink*>(png_get_error_ptr(png));
  std::snprintf(sink->message, sizeof(sink->message), "%s", msg);
  png_longjmp(png, 1);
}
inline void on_warning(png_structp, png_const_charp) {}

}  // namespace rgbdtam::png_hooks
