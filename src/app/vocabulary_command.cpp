#include "vocabulary_command.hpp"

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include "config_files.hpp"
#include "frontend_frames.hpp"
#include "rgbdtam/core/features.hpp"
#include "rgbdtam/hal/file.hpp"

namespace rgbdtam {
namespace {

struct TrainOptions {
  std::vector<const char*> sequences;
  const char* config = nullptr;
  const char* out = nullptr;
  int every = 5;  // frames
  int branching = 10;
  int depth = 4;
};

bool parse_whole(const char* text, int lo, int hi, int* out) {
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || errno != 0 || v < lo || v > hi) return false;
  *out = static_cast<int>(v);
  return true;
}

// The descriptors of every `every`-th frame of one sequence, one image per entry.
Status collect(const char* sequence, const Params& p, int every,
               std::vector<std::vector<Descriptor>>* images) {
  FrontendFrames frames;
  RGBDTAM_RETURN_IF_ERROR(frames.open(sequence, p));
  FeatureExtractor extractor;
  FeatureOptions opt;
  opt.max_features = p.loop.features;
  extractor.allocate(p.camera.width_px, p.camera.height_px, opt);
  FixedVector<Feature> features;
  features.reserve_once(opt.max_features);
  for (int i = 0; i < frames.count(); i += every) {
    if (!frames.load(i)) continue;
    const FramePyramid& frame = frames.frame();
    extractor.extract(frame.gray(0), frame.inverse_depth(0), frame.intrinsics(0), &features);
    std::vector<Descriptor> image;
    for (const Feature& feature : features) image.push_back(feature.descriptor);
    if (!image.empty()) images->push_back(std::move(image));
  }
  return Status::ok();
}

int train(const TrainOptions& o) {
  Params p;
  Status s = read_params_file(o.config, &p);
  std::vector<std::vector<Descriptor>> images;
  size_t descriptors = 0;
  for (const char* sequence : o.sequences) {
    if (!s.is_ok()) break;
    const size_t before = images.size();
    s = collect(sequence, p, o.every, &images);
    size_t n = 0;
    for (size_t i = before; i < images.size(); ++i) n += images[i].size();
    descriptors += n;
    if (s.is_ok()) {
      std::printf("%s: %zu images, %zu descriptors\n", sequence, images.size() - before, n);
    }
  }
  if (s.is_ok() && descriptors == 0) {
    s = Status::error(StatusCode::kInvalidArgument, "no features with depth in the sequences");
  }
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam vocabulary train: %s\n", s.message());
    return 1;
  }
  const Vocabulary v = Vocabulary::train(images, o.branching, o.depth);
  std::unique_ptr<uint8_t[]> bytes(new uint8_t[v.serialized_size()]);
  v.serialize(bytes.get());
  char buffer[1 << 16];
  OutputFile out;
  s = out.open(o.out, buffer, sizeof(buffer));
  if (s.is_ok()) {
    s = out.check(std::fwrite(bytes.get(), 1, v.serialized_size(), out.stream()) ==
                  v.serialized_size());
  }
  if (s.is_ok()) s = out.commit();
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam vocabulary train: %s\n", s.message());
    return 1;
  }
  std::printf(
      "vocabulary: %d words, %d nodes (k = %d, L = %d) from %zu descriptors of %zu "
      "images; %zu bytes to %s\n",
      v.words(), v.nodes(), o.branching, o.depth, descriptors, images.size(), v.serialized_size(),
      o.out);
  return 0;
}

}  // namespace

int vocabulary_command(int argc, char** argv) {
  if (argc < 1 || std::strcmp(argv[0], "train") != 0) {
    std::fprintf(stderr,
                 "usage: rgbdtam vocabulary train <sequence-dir>... --config <file> --out <file>\n"
                 "                                [--every N] [--branching K] [--depth L]\n");
    return 2;
  }
  TrainOptions o;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (std::strcmp(argv[i], "--config") == 0 && has_value) {
      o.config = argv[++i];
    } else if (std::strcmp(argv[i], "--out") == 0 && has_value) {
      o.out = argv[++i];
    } else if (std::strcmp(argv[i], "--every") == 0 && has_value) {
      if (!parse_whole(argv[++i], 1, INT_MAX, &o.every)) {
        std::fprintf(stderr, "rgbdtam vocabulary train: --every needs a whole number >= 1\n");
        return 2;
      }
    } else if (std::strcmp(argv[i], "--branching") == 0 && has_value) {
      if (!parse_whole(argv[++i], 2, 64, &o.branching)) {
        std::fprintf(stderr, "rgbdtam vocabulary train: --branching needs 2 to 64\n");
        return 2;
      }
    } else if (std::strcmp(argv[i], "--depth") == 0 && has_value) {
      if (!parse_whole(argv[++i], 1, 8, &o.depth)) {
        std::fprintf(stderr, "rgbdtam vocabulary train: --depth needs 1 to 8\n");
        return 2;
      }
    } else if (argv[i][0] == '-') {
      std::fprintf(stderr, "rgbdtam vocabulary train: unknown argument '%s'\n", argv[i]);
      return 2;
    } else {
      o.sequences.push_back(argv[i]);
    }
  }
  if (o.sequences.empty() || o.config == nullptr || o.out == nullptr) {
    std::fprintf(stderr,
                 "rgbdtam vocabulary train: needs at least one sequence, --config and --out\n");
    return 2;
  }
  return train(o);
}

}  // namespace rgbdtam
