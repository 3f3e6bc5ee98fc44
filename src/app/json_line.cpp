#include "json_line.hpp"

#include <cmath>

namespace rgbdtam {

void write_json_string(std::FILE* out, const char* value) {
  std::fputc('"', out);
  for (const unsigned char* c = reinterpret_cast<const unsigned char*>(value); *c != 0; ++c) {
    if (*c == '"' || *c == '\\') {
      std::fprintf(out, "\\%c", *c);
    } else if (*c < 0x20) {
      std::fprintf(out, "\\u%04x", *c);
    } else {
      std::fputc(*c, out);
    }
  }
  std::fputc('"', out);
}

void JsonLine::key(const char* name) {
  std::fprintf(out_, "%s\"%s\": ", first_ ? "{" : ", ", name);
  first_ = false;
}

JsonLine& JsonLine::text(const char* name, const char* value) {
  key(name);
  write_json_string(out_, value);
  return *this;
}

JsonLine& JsonLine::number(const char* name, double value, int decimals) {
  key(name);
  if (std::isfinite(value)) {
    std::fprintf(out_, "%.*f", decimals, value);
  } else {
    std::fprintf(out_, "null");
  }
  return *this;
}

JsonLine& JsonLine::integer(const char* name, long long value) {
  key(name);
  std::fprintf(out_, "%lld", value);
  return *this;
}

JsonLine& JsonLine::boolean(const char* name, bool value) {
  key(name);
  std::fprintf(out_, "%s", value ? "true" : "false");
  return *this;
}

std::FILE* JsonLine::member(const char* name) {
  key(name);
  return out_;
}

void JsonLine::end() {
  std::fprintf(out_, first_ ? "{}\n" : "}\n");
  first_ = true;
}

}  // namespace rgbdtam
