#include "rgbdtam/hal/fakenect_dump.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "rgbdtam/hal/freenect_source.hpp"

namespace rgbdtam {
namespace {
constexpr int kLineBytes = 256;
constexpr int kHeaderBytes = 64;  // "P6 640 480 255\n" and the like
// The bytes after the header that fakenect copies for each frame (11-bit depth as 16 bits, RGB).
constexpr size_t kPixels = size_t{FreenectSource::kWidth} * FreenectSource::kHeight;
constexpr size_t kDepthFrameBytes = kPixels * 2;
constexpr size_t kColourFrameBytes = kPixels * 3;

// The line as a message can show it: non-printable bytes as '?', at most 60 of them.
void printable(const char* line, char* out, size_t out_bytes) {
  size_t n = 0;
  for (; line[n] != '\0' && n + 1 < out_bytes && n < 60; ++n) {
    const unsigned char c = static_cast<unsigned char>(line[n]);
    out[n] = c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?';
  }
  out[n] = '\0';
}

// The frame file's size past its one-line header, or an error.
Status frame_bytes(const char* path, size_t file_bytes, size_t* out) {
  std::FILE* f = std::fopen(path, "rb");
  if (f == nullptr)
    return Status::error(StatusCode::kIoError, "%s: %s", path, std::strerror(errno));
  char header[kHeaderBytes];
  const size_t n = std::fread(header, 1, sizeof(header), f);
  std::fclose(f);
  const void* newline = std::memchr(header, '\n', n);
  if (newline == nullptr) {
    return Status::error(StatusCode::kCorrupt, "%s: no PNM header line", path);
  }
  *out = file_bytes - static_cast<size_t>(static_cast<const char*>(newline) - header + 1);
  return Status::ok();
}

Status check_entry(const char* dir, const char* line, int number) {
  char shown[64];
  printable(line, shown, sizeof(shown));
  char type = 0;
  double time_s = 0.0;
  unsigned ticks = 0;
  bool plain = true;
  for (const char* c = line; *c != '\0'; ++c) {
    plain = plain && *c > 0x20 && *c < 0x7f && *c != '/';
  }
  if (!plain || std::sscanf(line, "%c-%lf-%u-", &type, &time_s, &ticks) != 3 ||
      (type != 'd' && type != 'r' && type != 'a')) {
    return Status::error(StatusCode::kCorrupt,
                         "%s/INDEX.txt line %d is not a fakenect entry (d-, r- or a-<time>-"
                         "<timestamp>-<name>): '%s'",
                         dir, number, shown);
  }
  char path[2 * kLineBytes];
  std::snprintf(path, sizeof(path), "%s/%s", dir, line);
  struct stat st {};
  if (stat(path, &st) != 0 || !S_ISREG(st.st_mode)) {
    return Status::error(StatusCode::kNotFound, "%s/INDEX.txt line %d: %s is not a file", dir,
                         number, path);
  }
  if (type == 'a') return Status::ok();  // fakenect warns about an odd size itself
  size_t bytes = 0;
  RGBDTAM_RETURN_IF_ERROR(frame_bytes(path, static_cast<size_t>(st.st_size), &bytes));
  const size_t needed = type == 'd' ? kDepthFrameBytes : kColourFrameBytes;
  if (bytes < needed) {
    return Status::error(StatusCode::kCorrupt,
                         "%s/INDEX.txt line %d: %s holds %zu bytes of a %zu-byte %s frame", dir,
                         number, path, bytes, needed, type == 'd' ? "depth" : "colour");
  }
  return Status::ok();
}
}  // namespace

Status check_fakenect_dump(const char* dir) {
  char index[2 * kLineBytes];
  std::snprintf(index, sizeof(index), "%s/INDEX.txt", dir);
  struct stat st {};
  std::FILE* f = stat(index, &st) == 0 && S_ISREG(st.st_mode) ? std::fopen(index, "rb") : nullptr;
  if (f == nullptr) {
    return Status::error(StatusCode::kNotFound, "'%s' is not a fakenect dump (no INDEX.txt)", dir);
  }
  char line[kLineBytes + 2];
  int number = 0, frames = 0;
  Status s = Status::ok();
  while (s.is_ok() && std::fgets(line, sizeof(line), f) != nullptr) {
    ++number;
    const size_t length = std::strlen(line);
    if (length > 0 && line[length - 1] == '\n') {
      line[length - 1] = '\0';
    } else if (!std::feof(f)) {
      s = Status::error(StatusCode::kCorrupt, "%s/INDEX.txt line %d is longer than %d bytes", dir,
                        number, kLineBytes);
      break;
    }
    if (line[0] == '\0') break;  // fakenect stops at an empty line
    s = check_entry(dir, line, number);
    frames += line[0] == 'd' || line[0] == 'r' ? 1 : 0;
  }
  std::fclose(f);
  RGBDTAM_RETURN_IF_ERROR(s);
  if (frames == 0) {
    return Status::error(StatusCode::kCorrupt, "%s/INDEX.txt lists no frames", dir);
  }
  return Status::ok();
}

}  // namespace rgbdtam
