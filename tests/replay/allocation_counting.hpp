#pragma once
// Counts every call to malloc, calloc, realloc and the aligned allocators (through the linker's
// --wrap, which in a static link also reaches libc's, libstdc++'s, libpng's and zlib's own
// calls) and every operator new, while armed. Included by exactly one file of each allocation
// test executable (the wrappers and the replacement operator new are defined here).
#include <atomic>
#include <cstdlib>
#include <initializer_list>
#include <new>
#include <string>

#include "config_files.hpp"
#include "replay_job.hpp"
#include "replay_runner.hpp"
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
// The replacement operator new above allocates with malloc, so free is the matching release;
// GCC 12 (aarch64, once inlined into a vector's destructor) cannot see through the replacement.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace rgbdtam {
namespace {

// Every replay_and_evaluate of the binary counts its run's allocations.
[[maybe_unused]] const bool g_replays_counted = [] {
  testing::count_allocations_in_replays({[] {
                                           g_calls = 0;
                                           g_bytes = 0;
                                           g_armed = true;
                                         },
                                         [] {
                                           g_armed = false;
                                           return g_calls.load();
                                         }});
  return true;
}();

// Replays a sequence (the committed clip unless given) with the given config overrides,
// counting allocations from the end of init to the end of the run (mapper thread joined).
// Returns the count.
[[maybe_unused]] long count_allocations_after_init(std::initializer_list<const char*> overrides,
                                                   ReplayJob* job,
                                                   std::string seq = std::string()) {
  ReplayOptions opt;
  const bool clip = seq.empty();
  if (clip) seq = testing::source_path("data/tum_fr1_xyz_clip");
  const std::string config = testing::source_path("config/tum_fr1.conf");
  const std::string trajectory = testing::make_temp_dir("alloc") + "/trajectory.txt";
  opt.sequence = seq.c_str();
  opt.trajectory_path = trajectory.c_str();
  opt.progress = false;
  EXPECT_TRUE(read_params_file(config.c_str(), &opt.params).is_ok());
  for (const char* o : overrides) EXPECT_TRUE(set_param(o, "test", &opt.params).is_ok()) << o;
  EXPECT_TRUE(job->init(opt).is_ok());
  g_calls = 0;
  g_bytes = 0;
  g_armed = true;  // init is complete: from here on, nothing may allocate
  int frames = 0;
  while (job->step()) ++frames;
  EXPECT_TRUE(job->finish().is_ok());
  g_armed = false;
  if (clip) {
    EXPECT_EQ(frames, 50);
    EXPECT_EQ(job->counters().tracked, 50u);
  }
  EXPECT_GT(job->counters().keyframes, 1u) << "keyframe creation must be part of the counted run";
  return g_calls.load();
}

}  // namespace
}  // namespace rgbdtam
