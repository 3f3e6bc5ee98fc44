#pragma once
// Four floats, one SSE2 or NEON register: GCC and Clang lower the arithmetic on them to either,
// for the per-pixel and per-point loops the vectoriser leaves scalar.

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

}  // namespace rgbdtam
