#include "rgbdtam/hal/tum_timestamp.hpp"

#include <cstdint>
#include <cstdio>

namespace rgbdtam {

const char* parse_seconds_ns(const char* s, int64_t* ns) {
  while (*s == ' ' || *s == '\t') ++s;
  bool negative = false;
  if (*s == '-') {
    negative = true;
    ++s;
  }
  int64_t sec = 0;
  int digits = 0;
  constexpr int64_t kMaxSeconds = INT64_MAX / 1'000'000'000LL - 1;  // room for the fraction
  bool saturated = false;
  while (*s >= '0' && *s <= '9') {
    if (!saturated) sec = sec * 10 + (*s - '0');
    saturated = saturated || sec > kMaxSeconds;
    ++s;
    ++digits;
  }
  int64_t frac = 0;
  int frac_digits = 0;
  if (*s == '.') {
    ++s;
    while (*s >= '0' && *s <= '9') {
      if (frac_digits < 9) {
        frac = frac * 10 + (*s - '0');
        ++frac_digits;
      }
      ++s;
      ++digits;
    }
  }
  if (digits == 0) return nullptr;
  for (int i = frac_digits; i < 9; ++i) frac *= 10;
  const int64_t magnitude = saturated ? INT64_MAX : sec * 1'000'000'000LL + frac;
  *ns = negative ? -magnitude : magnitude;
  return s;
}

void format_seconds(int64_t ns, char* buf, int size) {
  const char* sign = ns < 0 ? "-" : "";
  const int64_t a = ns < 0 ? -ns : ns;
  const long long sec = a / 1'000'000'000LL;
  const long long frac = a % 1'000'000'000LL;
  if (frac % 1000 == 0) {
    std::snprintf(buf, static_cast<size_t>(size), "%s%lld.%06lld", sign, sec, frac / 1000);
  } else {
    std::snprintf(buf, static_cast<size_t>(size), "%s%lld.%09lld", sign, sec, frac);
  }
}

}  // namespace rgbdtam
