#pragma once
// Line splitting for every text format read here: LF, CRLF and CR-only line endings alike.

#include <cstddef>
#include <cstring>

namespace rgbdtam {

// The line starting at `text` has *length characters (its ending excluded). Returns where the
// next line starts, or nullptr when this was the last.
inline const char* split_line(const char* text, size_t* length) {
  const char* end = text + std::strcspn(text, "\r\n");
  *length = static_cast<size_t>(end - text);
  if (*end == '\0') return nullptr;
  return end + (end[0] == '\r' && end[1] == '\n' ? 2 : 1);
}

}  // namespace rgbdtam
