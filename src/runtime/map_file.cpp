#include "rgbdtam/runtime/map_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rgbdtam/core/byte_io.hpp"

namespace rgbdtam {
namespace {
constexpr char kMagic[8] = {'R', 'G', 'B', 'D', 'T', 'M', 'A', 'P'};
constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 + 32 + 8 + 16 + 8 + 8 + 96 + 48;
constexpr size_t kChecksumBytes = 4;
// A place without its features, words and view; a feature; a word; an edge.
constexpr size_t kPlaceBytes = 4 + 8 + 7 * 8 + 4 + 4;
constexpr size_t kFeatureBytes = 32 + 5 * 4, kWordBytes = 8, kEdgeBytes = 8 + 4 + 7 * 8 + 36 * 8;
constexpr int kLargestSide = 1 << 14;
constexpr uint32_t kMostWords = 1u << 22;  // the shipped vocabulary has 10^4
// Ranges a map this firmware made always keeps, checked whatever the checksum says: a place
// 1e300 m away reached the link as a pose, and ids near 2^32 wrapped onto the map's own.
constexpr double kMostMetresFromOrigin = 1e4;    // no indoor map reaches 10 km
constexpr uint32_t kMostKeyframeIds = 1u << 31;  // and ids leave room for as many new ones
constexpr int kLastEdgeKind = static_cast<int>(EdgeKind::kReuse);

// Fields through to the sink, hashed on the way.
class HashingWriter {
 public:
  explicit HashingWriter(ByteSink* sink) : sink_(sink) {}
  template <typename T>
  void put(T v) {
    bytes(&v, sizeof(T));
  }
  void bytes(const void* data, size_t size) {
    if (!ok_) return;
    hash_ = fnv1a(static_cast<const uint8_t*>(data), size, hash_);
    ok_ = sink_->write(data, size);
  }
  void pose(const SE3& T) {
    const Eigen::Quaterniond& q = T.quaternion();
    for (const double v : {q.w(), q.x(), q.y(), q.z()}) put(v);
    for (int i = 0; i < 3; ++i) put(T.translation()[i]);
  }
  bool ok() const { return ok_; }
  uint32_t hash() const { return hash_; }

 private:
  ByteSink* sink_;
  uint32_t hash_ = kFnv1aStart;
  bool ok_ = true;
};

bool read_pose(ByteReader* r, SE3* T) {
  double q[4], t[3];
  for (double& v : q) v = r->get<double>();
  for (double& v : t) v = r->get<double>();
  for (const double v : q) {
    if (!std::isfinite(v)) return false;
  }
  for (const double v : t) {
    if (!(std::fabs(v) <= kMostMetresFromOrigin)) return false;  // NaN and inf too
  }
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (std::fabs(norm - 1.0) > 1e-6) return false;
  *T = SE3(Eigen::Quaterniond(q[0], q[1], q[2], q[3]), Vector3d(t[0], t[1], t[2]));
  return true;
}

bool alive(const PlaceStore& places, const LoopModule::Edge& e) {
  return places.get(e.from) != nullptr && places.get(e.to) != nullptr;
}

Status corrupt(const char* what, uint32_t index) {
  return Status::error(StatusCode::kCorrupt, "map file: %s %u is damaged", what, index);
}

bool same_camera(const PinholeIntrinsics& a, const PinholeIntrinsics& b) {
  auto close = [](double x, double y) {
    return std::fabs(x - y) <= 1e-9 * std::max(1.0, std::fabs(y));
  };
  return a.width_px == b.width_px && a.height_px == b.height_px && close(a.fx_px, b.fx_px) &&
         close(a.fy_px, b.fy_px) && close(a.cx_px, b.cx_px) && close(a.cy_px, b.cy_px);
}
// The places after the header, into a store with room for them; r is left at the edges.
Status read_places(const MapFileInfo& m, ByteReader* r, PlaceStore* places) {
  const size_t view_pixels = static_cast<size_t>(m.view_width_px) * m.view_height_px;
  std::lock_guard<std::mutex> lock(places->mutex());
  for (uint32_t i = 0; i < m.places; ++i) {
    PlaceRecord* p = places->begin_insert();
    p->keyframe_id = r->get<uint32_t>();
    p->timestamp_ns = r->get<int64_t>();
    const bool ids_grow =
        i == 0 || p->keyframe_id > places->in_order(places->size() - 1).keyframe_id;
    if (!read_pose(r, &p->T_w_k) || !ids_grow || p->keyframe_id >= m.next_keyframe_id) {
      return corrupt("place", i);
    }
    const uint32_t features = r->get<uint32_t>();
    if (features > m.most_features) return corrupt("place", i);
    for (uint32_t k = 0; k < features; ++k) {
      Feature f;
      for (uint64_t& b : f.descriptor.bits) b = r->get<uint64_t>();
      for (float* v : {&f.u_px, &f.v_px, &f.x_m, &f.y_m, &f.z_m}) *v = r->get<float>();
      if (!std::isfinite(f.x_m) || !std::isfinite(f.y_m) || !std::isfinite(f.z_m)) {
        return corrupt("place", i);
      }
      (void)p->features.push_back(f);
    }
    const uint32_t words = r->get<uint32_t>();
    if (words > static_cast<uint32_t>(p->bow.capacity())) return corrupt("place", i);
    for (uint32_t k = 0; k < words; ++k) {
      BowEntry e;
      e.word = r->get<uint32_t>();
      e.weight = r->get<float>();
      const bool sorted = k == 0 || e.word > p->bow[static_cast<int>(k) - 1].word;
      if (e.word >= m.vocabulary_words || !sorted || !std::isfinite(e.weight)) {
        return corrupt("place", i);
      }
      (void)p->bow.push_back(e);
    }
    r->bytes(p->view.gray.data(), view_pixels);
    r->bytes(p->view.inverse_depth.data(), sizeof(uint16_t) * view_pixels);
    if (!r->ok()) return corrupt("place", i);
    places->commit();
  }
  return Status::ok();
}
}  // namespace

Status write_map(const PlaceStore& places, const FixedVector<LoopModule::Edge>& edges,
                 MapFileInfo meta, ByteSink* out) {
  meta.places = static_cast<uint32_t>(places.size());
  meta.edges = 0;
  for (const LoopModule::Edge& e : edges) meta.edges += alive(places, e) ? 1 : 0;
  meta.most_features = 0;
  for (int k = 0; k < 3; ++k) {
    meta.lowest_m[k] = places.size() > 0 ? INFINITY : 0.0;
    meta.highest_m[k] = places.size() > 0 ? -INFINITY : 0.0;
  }
  for (int i = 0; i < places.size(); ++i) {
    const PlaceRecord& r = places.in_order(i);
    meta.most_features = std::max(meta.most_features, static_cast<uint32_t>(r.features.size()));
    meta.next_keyframe_id = std::max(meta.next_keyframe_id, r.keyframe_id + 1);
    for (int k = 0; k < 3; ++k) {
      meta.lowest_m[k] = std::min(meta.lowest_m[k], r.T_w_k.translation()[k]);
      meta.highest_m[k] = std::max(meta.highest_m[k], r.T_w_k.translation()[k]);
    }
  }
  const PinholeIntrinsics view = View::intrinsics(meta.camera);
  HashingWriter w(out);
  w.bytes(kMagic, sizeof(kMagic));
  w.put<uint32_t>(MapFileInfo::kVersion);
  w.put<uint32_t>(static_cast<uint32_t>(kHeaderBytes));
  w.put<uint32_t>(static_cast<uint32_t>(meta.camera.width_px));
  w.put<uint32_t>(static_cast<uint32_t>(meta.camera.height_px));
  for (const double v :
       {meta.camera.fx_px, meta.camera.fy_px, meta.camera.cx_px, meta.camera.cy_px}) {
    w.put(v);
  }
  for (const uint32_t v :
       {meta.vocabulary_checksum, meta.vocabulary_words, meta.places, meta.edges,
        meta.most_features, meta.next_keyframe_id, static_cast<uint32_t>(view.width_px),
        static_cast<uint32_t>(view.height_px)}) {
    w.put(v);
  }
  w.put<int64_t>(meta.written_unix_ns);
  meta.written_by[sizeof(meta.written_by) - 1] = '\0';
  w.bytes(meta.written_by, sizeof(meta.written_by));
  for (const double v : meta.lowest_m) w.put(v);
  for (const double v : meta.highest_m) w.put(v);

  for (int i = 0; i < places.size(); ++i) {
    const PlaceRecord& r = places.in_order(i);
    w.put<uint32_t>(r.keyframe_id);
    w.put<int64_t>(r.timestamp_ns);
    w.pose(r.T_w_k);
    w.put<uint32_t>(static_cast<uint32_t>(r.features.size()));
    for (const Feature& f : r.features) {
      for (const uint64_t b : f.descriptor.bits) w.put(b);
      for (const float v : {f.u_px, f.v_px, f.x_m, f.y_m, f.z_m}) w.put(v);
    }
    w.put<uint32_t>(static_cast<uint32_t>(r.bow.size()));
    for (const BowEntry& e : r.bow) {
      w.put(e.word);
      w.put(e.weight);
    }
    w.bytes(r.view.gray.data(), static_cast<size_t>(r.view.gray.size()));
    w.bytes(r.view.inverse_depth.data(), sizeof(uint16_t) * r.view.inverse_depth.size());
  }
  for (const LoopModule::Edge& e : edges) {
    if (!alive(places, e)) continue;
    w.put<uint32_t>(places.get(e.from)->keyframe_id);
    w.put<uint32_t>(places.get(e.to)->keyframe_id);
    w.put<uint8_t>(static_cast<uint8_t>(e.kind));
    for (int k = 0; k < 3; ++k) w.put<uint8_t>(0);
    w.pose(e.T_from_to);
    for (int row = 0; row < 6; ++row) {
      for (int col = 0; col < 6; ++col) w.put<double>(e.information(row, col));
    }
  }
  const uint32_t checksum = w.hash();
  w.bytes(&checksum, sizeof(checksum));
  if (!w.ok()) return Status::error(StatusCode::kIoError, "map file: write failed");
  return Status::ok();
}

size_t map_file_bytes_at_most(const Params& params) {
  const size_t per_place =
      kPlaceBytes + static_cast<size_t>(params.loop.features) * (kFeatureBytes + kWordBytes) +
      View::bytes(params.camera);
  const size_t places = static_cast<size_t>(params.loop.places);
  return kHeaderBytes + places * per_place + places * LoopModule::kEdgesPerPlace * kEdgeBytes +
         kChecksumBytes;
}

Status read_map_info(const uint8_t* data, size_t size, MapFileInfo* info) {
  if (size < sizeof(kMagic) + 8 || std::memcmp(data, kMagic, sizeof(kMagic)) != 0) {
    return Status::error(StatusCode::kCorrupt, "not an rgbdtam map file (no RGBDTMAP header)");
  }
  ByteReader r(data + sizeof(kMagic), size - sizeof(kMagic));
  MapFileInfo m;
  m.version = r.get<uint32_t>();
  if (m.version != MapFileInfo::kVersion) {
    return Status::error(StatusCode::kInvalidArgument,
                         "map file format version %u; this build reads version %u", m.version,
                         MapFileInfo::kVersion);
  }
  if (r.get<uint32_t>() != kHeaderBytes || size < kHeaderBytes + kChecksumBytes) {
    return Status::error(StatusCode::kCorrupt, "map file: header damaged or file cut short");
  }
  uint32_t checksum;
  std::memcpy(&checksum, data + size - kChecksumBytes, kChecksumBytes);
  if (checksum != fnv1a(data, size - kChecksumBytes)) {
    return Status::error(StatusCode::kCorrupt,
                         "map file checksum mismatch (damaged, or cut short: %zu bytes)", size);
  }
  m.camera.width_px = static_cast<int>(r.get<uint32_t>());
  m.camera.height_px = static_cast<int>(r.get<uint32_t>());
  for (double* v : {&m.camera.fx_px, &m.camera.fy_px, &m.camera.cx_px, &m.camera.cy_px}) {
    *v = r.get<double>();
  }
  for (uint32_t* v : {&m.vocabulary_checksum, &m.vocabulary_words, &m.places, &m.edges,
                      &m.most_features, &m.next_keyframe_id, &m.view_width_px, &m.view_height_px}) {
    *v = r.get<uint32_t>();
  }
  m.written_unix_ns = r.get<int64_t>();
  r.bytes(m.written_by, sizeof(m.written_by));
  m.written_by[sizeof(m.written_by) - 1] = '\0';
  for (double& v : m.lowest_m) v = r.get<double>();
  for (double& v : m.highest_m) v = r.get<double>();
  m.file_bytes = size;
  // Counts a file of this size cannot hold are damage, whatever the checksum says: nothing is
  // sized from them.
  const bool camera_ok = m.camera.width_px >= 16 && m.camera.height_px >= 16 &&
                         m.camera.width_px <= kLargestSide && m.camera.height_px <= kLargestSide &&
                         std::isfinite(m.camera.fx_px) && std::isfinite(m.camera.fy_px) &&
                         std::isfinite(m.camera.cx_px) && std::isfinite(m.camera.cy_px) &&
                         m.camera.fx_px > 0 && m.camera.fy_px > 0;
  if (!camera_ok) return Status::error(StatusCode::kCorrupt, "map file: camera model damaged");
  const PinholeIntrinsics view = View::intrinsics(m.camera);
  if (m.view_width_px != static_cast<uint32_t>(view.width_px) ||
      m.view_height_px != static_cast<uint32_t>(view.height_px)) {
    return Status::error(StatusCode::kCorrupt, "map file: views of %ux%u, expected %dx%d",
                         m.view_width_px, m.view_height_px, view.width_px, view.height_px);
  }
  // The largest place holds most_features features.
  const uint64_t least_bytes = kHeaderBytes + kChecksumBytes +
                               uint64_t{m.places} * (kPlaceBytes + View::bytes(m.camera)) +
                               (m.places > 0 ? uint64_t{m.most_features} * kFeatureBytes : 0) +
                               uint64_t{m.edges} * kEdgeBytes;
  if (least_bytes > size || m.vocabulary_words > kMostWords) {
    return Status::error(StatusCode::kCorrupt, "map file: header counts damaged");
  }
  if (m.next_keyframe_id > kMostKeyframeIds) {
    return Status::error(StatusCode::kCorrupt,
                         "map file: next keyframe id %u is out of range (at most %u)",
                         m.next_keyframe_id, kMostKeyframeIds);
  }
  for (int k = 0; k < 3; ++k) {
    if (!(std::fabs(m.lowest_m[k]) <= kMostMetresFromOrigin) ||
        !(std::fabs(m.highest_m[k]) <= kMostMetresFromOrigin)) {
      return Status::error(StatusCode::kCorrupt,
                           "map file: its bounds reach beyond %.0f m from the origin",
                           kMostMetresFromOrigin);
    }
  }
  *info = m;
  return Status::ok();
}

Status load_map(const uint8_t* data, size_t size, const Params& params,
                const Vocabulary& vocabulary, PlaceStore* places, LoopModule* loop,
                MapFileInfo* info) {
  RGBDTAM_ASSERT(places->size() == 0 && loop->edges().empty(), "a map loads into empty stores");
  RGBDTAM_RETURN_IF_ERROR(read_map_info(data, size, info));
  const MapFileInfo& m = *info;
  if (!same_camera(m.camera, params.camera)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "map file was made with another camera (%dx%d, fx %.2f) than this "
                         "configuration's (%dx%d, fx %.2f)",
                         m.camera.width_px, m.camera.height_px, m.camera.fx_px,
                         params.camera.width_px, params.camera.height_px, params.camera.fx_px);
  }
  if (m.vocabulary_checksum != vocabulary.checksum() ||
      m.vocabulary_words != static_cast<uint32_t>(vocabulary.words())) {
    return Status::error(StatusCode::kInvalidArgument,
                         "map file was described with another vocabulary (%u words, checksum "
                         "%08x) than loop.vocabulary's (%d words, checksum %08x)",
                         m.vocabulary_words, m.vocabulary_checksum, vocabulary.words(),
                         vocabulary.checksum());
  }
  if (m.places > static_cast<uint32_t>(places->capacity())) {
    return Status::error(StatusCode::kOutOfRange,
                         "map file holds %u places; loop.places is %d: set it to at least %u",
                         m.places, places->capacity(), m.places);
  }
  if (m.most_features > static_cast<uint32_t>(params.loop.features)) {
    return Status::error(StatusCode::kOutOfRange,
                         "map file has places of %u features; loop.features is %d: set it to at "
                         "least %u",
                         m.most_features, params.loop.features, m.most_features);
  }
  if (m.edges > static_cast<uint32_t>(loop->edges().capacity())) {
    return Status::error(StatusCode::kOutOfRange,
                         "map file holds %u graph edges; this configuration's graph holds %d "
                         "(4 per place of loop.places)",
                         m.edges, loop->edges().capacity());
  }

  ByteReader r(data + kHeaderBytes, size - kHeaderBytes - kChecksumBytes);
  RGBDTAM_RETURN_IF_ERROR(read_places(m, &r, places));
  for (uint32_t i = 0; i < m.edges; ++i) {
    const int from = places->order_of(r.get<uint32_t>());
    const int to = places->order_of(r.get<uint32_t>());
    const int kind = r.get<uint8_t>();
    for (int k = 0; k < 3; ++k) (void)r.get<uint8_t>();
    LoopModule::Edge e;
    e.kind = static_cast<EdgeKind>(kind);
    bool ok =
        read_pose(&r, &e.T_from_to) && from >= 0 && to >= 0 && from != to && kind <= kLastEdgeKind;
    for (int row = 0; row < 6; ++row) {
      for (int col = 0; col < 6; ++col) {
        e.information(row, col) = r.get<double>();
        ok = ok && std::isfinite(e.information(row, col));
      }
    }
    if (!ok || !r.ok()) return corrupt("edge", i);
    e.from = places->handle(from);
    e.to = places->handle(to);
    (void)loop->restore_edge(e);
  }
  if (r.left() != 0) {
    return Status::error(StatusCode::kCorrupt, "map file: %zu bytes after the last edge", r.left());
  }
  return Status::ok();
}

Status read_map_places(const uint8_t* data, size_t size, PlaceStore* places, MapFileInfo* info) {
  RGBDTAM_RETURN_IF_ERROR(read_map_info(data, size, info));
  if (info->places == 0) return Status::error(StatusCode::kInvalidArgument, "map file: no places");
  // The store's index wants room for at least one feature and word.
  places->allocate(static_cast<int>(info->places),
                   static_cast<int>(std::max<uint32_t>(info->most_features, 1)),
                   static_cast<int>(std::max<uint32_t>(info->vocabulary_words, 1)), info->camera);
  ByteReader r(data + kHeaderBytes, size - kHeaderBytes - kChecksumBytes);
  return read_places(*info, &r, places);
}

}  // namespace rgbdtam
