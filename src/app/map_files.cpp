#include "map_files.hpp"

#include <cstdio>

#include "config_files.hpp"
#include "rgbdtam/hal/atomic_file.hpp"
#include "rgbdtam/hal/clock.hpp"

namespace rgbdtam {

Status read_map_file(const char* path, const Params& params, std::unique_ptr<uint8_t[]>* data,
                     size_t* size) {
  return read_binary_file(path, map_file_bytes_at_most(params), data, size);
}

MapFileInfo map_written_by(const char* written_by) {
  MapFileInfo meta;
  meta.written_unix_ns = unix_time_ns();
  std::snprintf(meta.written_by, sizeof(meta.written_by), "%s", written_by);
  return meta;
}

Status save_map_file(const char* path, const SlamSystem& system, const char* written_by) {
  AtomicFileWriter file;
  RGBDTAM_RETURN_IF_ERROR(file.init(path));
  RGBDTAM_RETURN_IF_ERROR(file.begin());
  (void)system.write_map(map_written_by(written_by), &file);  // commit() names a failed write
  return file.commit();
}

}  // namespace rgbdtam
