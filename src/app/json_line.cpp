#include "json_line.hpp"

#include <cmath>

namespace rgbdtam {

void JsonLine::key(const char* name) {
  std::printf("%s\"%s\": ", first_ ? "{" : ", ", name);
  first_ = false;
}

JsonLine& JsonLine::text(const char* name, const char* value) {
  key(name);
  std::putchar('"');
  for (const unsigned char* c = reinterpret_cast<const unsigned char*>(value); *c != 0; ++c) {
    if (*c == '"' || *c == '\\') {
      std::printf("\\%c", *c);
    } else if (*c < 0x20) {
      std::printf("\\u%04x", *c);
    } else {
      std::putchar(*c);
    }
  }
  std::putchar('"');
  return *this;
}

JsonLine& JsonLine::number(const char* name, double value, int decimals) {
  key(name);
  if (std::isfinite(value)) {
    std::printf("%.*f", decimals, value);
  } else {
    std::printf("null");
  }
  return *this;
}

JsonLine& JsonLine::integer(const char* name, long long value) {
  key(name);
  std::printf("%lld", value);
  return *this;
}

JsonLine& JsonLine::boolean(const char* name, bool value) {
  key(name);
  std::printf("%s", value ? "true" : "false");
  return *this;
}

void JsonLine::end() {
  std::printf(first_ ? "{}\n" : "}\n");
  first_ = true;
}

}  // namespace rgbdtam
