#pragma once
// One JSON object on one line of stdout, for --json outputs: strings escaped, and numbers
// that are not finite written as null (JSON has no inf or nan).
#include <cstdio>

namespace rgbdtam {

class JsonLine {
 public:
  JsonLine& text(const char* key, const char* value);
  JsonLine& number(const char* key, double value, int decimals = 4);
  JsonLine& integer(const char* key, long long value);
  JsonLine& boolean(const char* key, bool value);
  void end();  // closes the object and the line

 private:
  void key(const char* name);
  bool first_ = true;
};

}  // namespace rgbdtam
