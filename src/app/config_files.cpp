#include "config_files.hpp"

#include <sys/stat.h>

#include <cerrno>

#include <cstdio>
#include <cstring>

#include "rgbdtam/hal/file.hpp"

namespace rgbdtam {
namespace {
constexpr size_t kMaxConfigBytes = 1 << 20;
constexpr size_t kMaxVocabularyBytes = size_t{256} << 20;
}  // namespace

Status load_board(const char* board_dir, Board* out) {
  char path[kTextBytes + 16];
  std::snprintf(path, sizeof(path), "%s/board.conf", board_dir);
  char* text = nullptr;
  RGBDTAM_RETURN_IF_ERROR(read_text_file(path, kMaxConfigBytes, &text));
  const Status s = parse_board(text, path, board_dir, out);
  delete[] text;
  return s;
}

Status read_params_file(const char* path, Params* p) {
  char* text = nullptr;
  RGBDTAM_RETURN_IF_ERROR(read_text_file(path, kMaxConfigBytes, &text));
  const Status s = parse_params(text, path, p);
  delete[] text;
  return s;
}

Status read_binary_file(const char* path, size_t max_bytes, std::unique_ptr<uint8_t[]>* data,
                        size_t* size) {
  struct stat st;
  if (::stat(path, &st) != 0) {
    return Status::error(StatusCode::kNotFound, "%s: cannot open (%s)", path, std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) {
    return Status::error(StatusCode::kInvalidArgument, "%s: not a regular file", path);
  }
  if (static_cast<size_t>(st.st_size) > max_bytes) {
    return Status::error(StatusCode::kOutOfRange, "%s: larger than %zu MB", path, max_bytes >> 20);
  }
  const size_t capacity = static_cast<size_t>(st.st_size) + 1;
  data->reset(new uint8_t[capacity]);
  return read_file(path, data->get(), capacity, size);
}

bool load_vocabulary(const Params& params, Vocabulary* out, Status* error) {
  *error = Status::ok();
  if (!params.loop.enabled) return false;
  if (params.loop.vocabulary[0] == '\0') {
    // A configuration from before loop closure still runs, without it, and says so.
    std::fprintf(stderr,
                 "warning: no loop closure or relocalisation: the config names no "
                 "loop.vocabulary (set loop.enabled = false to silence this)\n");
    return false;
  }
  std::unique_ptr<uint8_t[]> data;
  size_t size = 0;
  *error = read_binary_file(params.loop.vocabulary, kMaxVocabularyBytes, &data, &size);
  if (!error->is_ok()) return false;
  const Status s = Vocabulary::parse(data.get(), size, out);
  if (!s.is_ok()) {
    *error = Status::error(s.code(), "%s: %s", params.loop.vocabulary, s.message());
    return false;
  }
  return true;
}

}  // namespace rgbdtam
