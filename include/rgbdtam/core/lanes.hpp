#pragma once
// Four floats, one SSE2 or NEON register: GCC and Clang lower the arithmetic on them to either,
// for the per-pixel and per-point loops the vectoriser leaves scalar.

#include <cstdint>
#include <cstring>

namespace rgbdtam {

constexpr int kLanes = 4;
using Lanes = float __attribute__((vector_size(16)));
static_assert(sizeof(Lanes) == kLanes * sizeof(float), "one float a lane");

inline Lanes load_lanes(const float* p) {
  Lanes v;
  std::memcpy(&v, p, sizeof(v));  // unaligned
  return v;
}
inline void store_lanes(Lanes v, float* p) { std::memcpy(p, &v, sizeof(v)); }

// Four int32s; a comparison of Lanes gives one (-1 where true, 0 where false).
using IntLanes = int32_t __attribute__((vector_size(16)));
inline void store_lanes(IntLanes v, int32_t* p) { std::memcpy(p, &v, sizeof(v)); }

}  // namespace rgbdtam
