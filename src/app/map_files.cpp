#include "map_files.hpp"

#include <time.h>

#include <cstdio>
#include <cstring>

#include "config_files.hpp"
#include "rgbdtam/hal/file.hpp"

namespace rgbdtam {
namespace {
class OutputFileSink : public ByteSink {
 public:
  explicit OutputFileSink(OutputFile* file) : file_(file) {}
  bool write(const void* data, size_t size) override {
    return file_->check(std::fwrite(data, 1, size, file_->stream()) == size).is_ok();
  }

 private:
  OutputFile* file_;
};
}  // namespace

Status read_map_file(const char* path, const Params& params, std::unique_ptr<uint8_t[]>* data,
                     size_t* size) {
  return read_binary_file(path, map_file_bytes_at_most(params), data, size);
}

Status save_map_file(const char* path, const SlamSystem& system, const char* written_by) {
  MapFileInfo meta;
  timespec now;
  clock_gettime(CLOCK_REALTIME, &now);
  meta.written_unix_ns = static_cast<int64_t>(now.tv_sec) * 1000000000 + now.tv_nsec;
  std::snprintf(meta.written_by, sizeof(meta.written_by), "%s", written_by);
  char buffer[1 << 16];  // the stdio buffer: no allocation
  OutputFile file;
  RGBDTAM_RETURN_IF_ERROR(file.open(path, buffer, sizeof(buffer)));
  OutputFileSink sink(&file);
  const Status s = system.write_map(meta, &sink);
  if (!s.is_ok()) return file.status().is_ok() ? s : file.status();
  return file.commit();
}

}  // namespace rgbdtam
