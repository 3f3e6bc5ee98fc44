// No heap allocation after init: replays the committed clip while counting every call to
// malloc, calloc, realloc and the aligned allocators (through the linker's --wrap, which in a
// static link also reaches libc's, libstdc++'s, libpng's and zlib's own calls) and every
// operator new.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "replay_job.hpp"
#include "rgbdtam/hal/file.hpp"
#include "test_paths.hpp"

namespace {
std::atomic<bool> g_armed{false};
std::atomic<long> g_calls{0};
std::atomic<long> g_bytes{0};
void* volatile g_escape = nullptr;  // keeps the self-check's allocations from being elided

void note(size_t n) {
  if (g_armed.load(std::memory_order_relaxed)) {
    g_calls.fetch_add(1);
    g_bytes.fetch_add(static_cast<long>(n));
  }
}
}  // namespace

extern "C" {
void* __real_malloc(size_t);
void* __real_calloc(size_t, size_t);
void* __real_realloc(void*, size_t);
void* __real_aligned_alloc(size_t, size_t);
int __real_posix_memalign(void**, size_t, size_t);
void* __real_memalign(size_t, size_t);
void* __wrap_malloc(size_t n) {
  note(n);
  return __real_malloc(n);
}
void* __wrap_calloc(size_t c, size_t n) {
  note(c * n);
  return __real_calloc(c, n);
}
void* __wrap_realloc(void* p, size_t n) {
  note(n);
  return __real_realloc(p, n);
}
void* __wrap_aligned_alloc(size_t a, size_t n) {
  note(n);
  return __real_aligned_alloc(a, n);
}
int __wrap_posix_memalign(void** p, size_t a, size_t n) {
  note(n);
  return __real_posix_memalign(p, a, n);
}
void* __wrap_memalign(size_t a, size_t n) {
  note(n);
  return __real_memalign(a, n);
}
}

void* operator new(size_t n) {
  note(n);
  void* p = __real_malloc(n == 0 ? 1 : n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](size_t n) { return operator new(n); }
void* operator new(size_t n, const std::nothrow_t&) noexcept {
  note(n);
  return __real_malloc(n == 0 ? 1 : n);
}
void* operator new[](size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }

namespace rgbdtam {
namespace {

TEST(Allocations, NoneWhileReplayingTheClipAfterInit) {
  // The counter itself must see allocations, or a zero below would prove nothing.
  g_armed = true;
  g_escape = std::malloc(64);
  std::free(g_escape);
  g_escape = new int(3);
  delete static_cast<int*>(g_escape);
  g_armed = false;
  ASSERT_EQ(g_calls.load(), 2) << "the malloc/new counters are not wired in";
  g_calls = 0;
  g_bytes = 0;

  ReplayOptions opt;
  const std::string seq = testing::source_path("data/tum_fr1_xyz_clip");
  const std::string config = testing::source_path("config/tum_fr1.conf");
  const std::string trajectory = testing::make_temp_dir("alloc") + "/trajectory.txt";
  opt.sequence = seq.c_str();
  opt.trajectory_path = trajectory.c_str();
  opt.progress = false;
  char* text = nullptr;
  ASSERT_TRUE(read_text_file(config.c_str(), 1 << 20, &text).is_ok());
  ASSERT_TRUE(parse_params(text, config.c_str(), &opt.params).is_ok());
  delete[] text;
  ReplayJob job;
  ASSERT_TRUE(job.init(opt).is_ok());

  g_armed = true;  // init is complete: from here on, nothing may allocate
  int frames = 0;
  while (job.step()) ++frames;
  g_armed = false;

  ASSERT_TRUE(job.finish().is_ok());
  EXPECT_EQ(frames, 50);
  EXPECT_EQ(job.counters().tracked, 50u);
  EXPECT_GT(job.counters().keyframes, 1u) << "keyframe creation must be part of the counted run";
  EXPECT_EQ(g_calls.load(), 0) << g_bytes.load() << " bytes allocated after init";
  std::printf(
      "allocations after init over %d frames: %ld (%ld bytes); PNG arena high water %zu B\n",
      frames, g_calls.load(), g_bytes.load(), job.source().png_arena_high_water());
}

}  // namespace
}  // namespace rgbdtam
