#pragma once
// TUM timestamps ("1305031102.175304", seconds) <-> integer nanoseconds, exactly.

#include <cstdint>

namespace rgbdtam {

// Stamps a recording can carry: Unix time from 1970 to 2096. The difference of any two stays
// far from int64 overflow.
constexpr int64_t kMaxStampNs = 4'000'000'000LL * 1'000'000'000LL;

// Parses a decimal seconds value with up to 9 fractional digits. Returns the end of the
// number, or nullptr if there is none. Beyond int64 nanoseconds it saturates: check the range.
const char* parse_seconds_ns(const char* s, int64_t* ns);
// Writes seconds with 6 decimals (9 when there is a sub-microsecond part); buf >= 32 bytes.
void format_seconds(int64_t ns, char* buf, int size);

}  // namespace rgbdtam
