#pragma once
// One JSON object on one line (stdout unless given a stream), for --json outputs and the
// monitor's state: strings escaped, and numbers that are not finite written as null (JSON has
// no inf or nan).
#include <cstdio>

namespace rgbdtam {

void write_json_string(std::FILE* out, const char* value);

class JsonLine {
 public:
  explicit JsonLine(std::FILE* out = stdout) : out_(out) {}
  JsonLine& text(const char* key, const char* value);
  JsonLine& number(const char* key, double value, int decimals = 4);
  JsonLine& integer(const char* key, long long value);
  JsonLine& boolean(const char* key, bool value);
  // Starts a member whose value the caller writes to stream() (an array, say).
  std::FILE* member(const char* key);
  void end();  // closes the object and the line

 private:
  void key(const char* name);
  std::FILE* out_;
  bool first_ = true;
};

}  // namespace rgbdtam
