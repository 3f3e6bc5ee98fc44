// libFuzzer target for the map file readers: read_map_info, load_map into stores sized by a
// small configuration (as replay and run load one), and read_map_places (as the exporters do).
// The input's last four bytes are replaced by its checksum, so that mutations reach past the
// checksum into the body; inputs of even size also get the configuration's camera and
// vocabulary in their header, so that load_map reads on past those checks.
// With RGBDTAM_WRITE_MAP_SEEDS=<dir> it writes seed maps there instead (tools/fuzz.sh).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "rgbdtam/core/byte_io.hpp"
#include "rgbdtam/runtime/map_file.hpp"

namespace rgbdtam {
namespace {

constexpr size_t kCameraAt = 16, kVocabularyAt = kCameraAt + 8 + 32;  // header offsets

struct Fixture {
  Params params;
  Vocabulary vocabulary;
  Fixture() {
    params.camera = {50.0, 50.0, 31.5, 23.5, 64, 48};
    params.loop.places = 4;
    params.loop.features = 16;
    std::ifstream f("data/vocabulary/tum-k10-l4.voc", std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), {});
    if (!Vocabulary::parse(bytes.data(), bytes.size(), &vocabulary).is_ok()) {
      std::fprintf(stderr, "fuzz_map_file: run from the repository (its vocabulary)\n");
      std::abort();
    }
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

int64_t no_clock() { return 0; }

class VectorSink : public ByteSink {
 public:
  bool write(const void* data, size_t size) override {
    const uint8_t* b = static_cast<const uint8_t*>(data);
    out.insert(out.end(), b, b + size);
    return true;
  }
  std::vector<uint8_t> out;
};

// Maps of 1 to 3 places with a few features and words, and edges between them.
void write_seeds(const char* dir) {
  const Fixture& fx = fixture();
  for (int places = 1; places <= 3; ++places) {
    PlaceStore store;
    store.allocate(4, 16, fx.vocabulary.words(), fx.params.camera);
    for (int i = 0; i < places; ++i) {
      std::lock_guard<std::mutex> lock(store.mutex());
      PlaceRecord* p = store.begin_insert();
      p->keyframe_id = static_cast<uint32_t>(3 * i);
      p->T_w_k = SE3(Eigen::Quaterniond::Identity(), Vector3d(0.1 * i, 0, 0));
      for (int k = 0; k < 2 + i; ++k) {
        Feature f;
        f.u_px = 10.f + k;
        f.z_m = 1.f;
        (void)p->features.push_back(f);
        (void)p->bow.push_back(BowEntry{static_cast<uint32_t>(7 * k + i), 0.5f});
      }
      for (int v = 0; v < p->view.inverse_depth.height(); ++v) {
        for (int u = 0; u < p->view.inverse_depth.width(); ++u) {
          p->view.inverse_depth.at(u, v) = static_cast<uint16_t>(4096 + u);
        }
      }
      store.commit();
    }
    FixedVector<LoopModule::Edge> edges;
    edges.reserve_once(4);
    for (int i = 1; i < places; ++i) {
      LoopModule::Edge e;
      e.from = store.handle(i - 1);
      e.to = store.handle(i);
      e.information = Matrix6d::Identity();
      e.kind = EdgeKind::kOdometry;
      (void)edges.push_back(e);
    }
    MapFileInfo meta;
    meta.camera = fx.params.camera;
    meta.vocabulary_checksum = fx.vocabulary.checksum();
    meta.vocabulary_words = static_cast<uint32_t>(fx.vocabulary.words());
    VectorSink sink;
    if (!write_map(store, edges, meta, &sink).is_ok()) std::abort();
    const std::string path = std::string(dir) + "/seed" + std::to_string(places) + ".map";
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(sink.out.data()),
               static_cast<std::streamsize>(sink.out.size()));
  }
}

}  // namespace
}  // namespace rgbdtam

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("RGBDTAM_WRITE_MAP_SEEDS")) {
    rgbdtam::write_seeds(dir);
    std::exit(0);
  }
  (void)rgbdtam::fixture();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rgbdtam;
  const Fixture& fx = fixture();
  std::vector<uint8_t> bytes(data, data + size);
  if (size >= kVocabularyAt + 8 && size % 2 == 0) {
    const uint32_t camera[2] = {64, 48};
    const double intrinsics[4] = {50.0, 50.0, 31.5, 23.5};
    const uint32_t vocabulary[2] = {fx.vocabulary.checksum(),
                                    static_cast<uint32_t>(fx.vocabulary.words())};
    std::memcpy(&bytes[kCameraAt], camera, sizeof(camera));
    std::memcpy(&bytes[kCameraAt + 8], intrinsics, sizeof(intrinsics));
    std::memcpy(&bytes[kVocabularyAt], vocabulary, sizeof(vocabulary));
  }
  if (size >= 4) {
    const uint32_t checksum = fnv1a(bytes.data(), size - 4);
    std::memcpy(&bytes[size - 4], &checksum, 4);
  }
  MapFileInfo info;
  // Both readers start with it: the stores are built only for inputs that pass it.
  if (!read_map_info(bytes.data(), size, &info).is_ok()) return 0;
  {
    PlaceStore places;
    places.allocate(fx.params.loop.places, fx.params.loop.features, fx.vocabulary.words(),
                    fx.params.camera);
    CorrectionQueue corrections;
    corrections.allocate(2, fx.params.loop.places);
    LoopModule loop;
    (void)loop.init(fx.params, &fx.vocabulary, &places, &corrections, no_clock);
    (void)load_map(bytes.data(), size, fx.params, fx.vocabulary, &places, &loop, &info);
  }
  PlaceStore exported;
  (void)read_map_places(bytes.data(), size, &exported, &info);
  return 0;
}
