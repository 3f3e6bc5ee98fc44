#pragma once
// Map files on disk for replay and run: read whole at init, written so that a power cut at any
// instant leaves either the old file or the new one, whole.

#include <memory>

#include "rgbdtam/runtime/slam_system.hpp"

namespace rgbdtam {

// The bytes of a map file, refused when larger than the stores params size can hold.
Status read_map_file(const char* path, const Params& params, std::unique_ptr<uint8_t[]>* data,
                     size_t* size);
// Loads `path` into a system's places and graph (a SlamSystem or the firmware, after init and
// before start).
template <typename System>
Status load_map_file(const char* path, const Params& params, System* system, MapFileInfo* info) {
  std::unique_ptr<uint8_t[]> data;
  size_t size = 0;
  RGBDTAM_RETURN_IF_ERROR(read_map_file(path, params, &data, &size));
  const Status s = system->load_map(data.get(), size, info);
  if (!s.is_ok()) return Status::error(s.code(), "%s: %s", path, s.message());
  return s;
}
// A map file's header fields for this build (written_by: version, commit, board) and now.
MapFileInfo map_written_by(const char* written_by);
// The system's map into `path`: written beside it, synced, renamed over it and the folder
// synced (AtomicFileWriter). After the system's finish().
Status save_map_file(const char* path, const SlamSystem& system, const char* written_by);

}  // namespace rgbdtam
