#pragma once
// A small, seeded, reproducible random sequence (Marsaglia's 32-bit xorshift): the same picks on
// every run and every board, which std's distributions do not promise.

#include <cstdint>

namespace rgbdtam {

inline uint32_t xorshift32(uint32_t* state) {
  *state ^= *state << 13;
  *state ^= *state >> 17;
  *state ^= *state << 5;
  return *state;
}

}  // namespace rgbdtam
