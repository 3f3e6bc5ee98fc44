#pragma once
// The map file: what relocalisation and loop closure need to find the camera in a map made by
// an earlier run (the places with their features, bags of words and views, and the keyframe
// graph's edges between them), so that a robot's world frame survives a reboot. The dense
// keyframes are not kept: relocalisation starts a new keyframe at a verified place, as it does
// for places older than the dense pool.
//
// Format (little-endian), version 1:
//   "RGBDTMAP", u32 version, u32 header bytes (from the start of the file);
//   header: u32 camera width, height, f64 fx, fy, cx, cy; u32 vocabulary checksum and words;
//           u32 places, edges, most features of a place, next keyframe id; u32 view width,
//           height; i64 written (Unix ns); char[96] writer (version, commit, board);
//           f64 x3 the places' lowest and x3 highest position;
//   each place: u32 keyframe id, i64 timestamp ns, f64 qw qx qy qz tx ty tz (T_w_k), u32
//           features, each (u64 x4 descriptor, f32 u v px, x y z m), u32 words, each (u32 word,
//           f32 weight), the view's grey (u8) then inverse depth (u16), row by row;
//   each edge: u32 from and to keyframe id, u8 kind, u8 x3 zero, f64 x7 T_from_to, f64 x36
//           information (row-major);
//   u32 FNV-1a of everything before it.
// Writing streams through a ByteSink (no buffer the size of the map); loading happens at init,
// into empty stores, and checks everything before the run starts.

#include <cstddef>
#include <cstdint>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/port/byte_sink.hpp"
#include "rgbdtam/runtime/loop_closing.hpp"

namespace rgbdtam {

struct MapFileInfo {
  static constexpr uint32_t kVersion = 1;
  uint32_t version = kVersion;
  PinholeIntrinsics camera;
  uint32_t vocabulary_checksum = 0;
  uint32_t vocabulary_words = 0;
  uint32_t places = 0;
  uint32_t edges = 0;
  uint32_t most_features = 0;     // of one place: loop.features must hold it
  uint32_t next_keyframe_id = 0;  // the next run's keyframes are numbered from here
  uint32_t view_width_px = 0, view_height_px = 0;
  int64_t written_unix_ns = 0;
  char written_by[96] = "";
  double lowest_m[3] = {0, 0, 0}, highest_m[3] = {0, 0, 0};  // the places' positions
  uint64_t file_bytes = 0;
};

// Writes the places the store remembers and the edges between them. meta gives the camera,
// vocabulary, time, writer and the next keyframe id (raised past the places' own here); the
// counts and extent are filled in here.
Status write_map(const PlaceStore& places, const FixedVector<LoopModule::Edge>& edges,
                 MapFileInfo meta, ByteSink* out);

// The largest map file stores sized by params can take (loop.places, loop.features).
size_t map_file_bytes_at_most(const Params& params);

// The header, after checking the magic, version, size and checksum.
Status read_map_info(const uint8_t* data, size_t size, MapFileInfo* info);

// Into empty stores, sized by params: refuses a map made with another camera or vocabulary, or
// one larger than the stores (with the numbers and the key to raise), never keeping part of it.
Status load_map(const uint8_t* data, size_t size, const Params& params,
                const Vocabulary& vocabulary, PlaceStore* places, LoopModule* loop,
                MapFileInfo* info);

// For tools (it allocates): the header and places of a map file, into `places`, sized here from
// the header. The edges are not read.
Status read_map_places(const uint8_t* data, size_t size, PlaceStore* places, MapFileInfo* info);

}  // namespace rgbdtam
