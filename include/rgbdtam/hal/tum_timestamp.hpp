#pragma once
// TUM timestamps ("1305031102.175304", seconds) <-> integer nanoseconds, exactly.

#include <cstdint>

namespace rgbdtam {

// Parses a decimal seconds value with up to 9 fractional digits. Returns the end of the
// number, or nullptr if there is none.
const char* parse_seconds_ns(const char* s, int64_t* ns);
// Writes seconds with 6 decimals (9 when there is a sub-microsecond part); buf >= 32 bytes.
void format_seconds(int64_t ns, char* buf, int size);

}  // namespace rgbdtam
