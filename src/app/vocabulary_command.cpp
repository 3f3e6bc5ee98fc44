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
#include "output_guard.hpp"
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
  bool augment = false;
};

// The variations of a frame that training may add, so that the words cover what the same
// place looks like to another camera or in another moment: mirrored (other arrangements of
// the same patterns), blurred (a moving hand-held camera), nearer (another scale: FAST has
// one), and dim and noisy (another exposure and sensor).
enum class Variation { kAsRecorded, kMirrored, kBlurred, kNearer, kDimNoisy };
constexpr Variation kVariations[] = {Variation::kAsRecorded, Variation::kMirrored,
                                     Variation::kBlurred, Variation::kNearer, Variation::kDimNoisy};

void vary(const ImageF& gray, const ImageF& inverse_depth, Variation v, uint32_t seed,
          ImageF* out_gray, ImageF* out_inverse_depth) {
  const int w = gray.width(), h = gray.height();
  constexpr float kZoom = 1.3f;   // nearer: the centre, enlarged
  constexpr int kBlurRadius = 2;  // a 5x5 box
  uint32_t state = seed * 2654435761u + 1u;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float g = gray.at(x, y), rho = inverse_depth.at(x, y);
      switch (v) {
        case Variation::kAsRecorded:
          break;
        case Variation::kMirrored:
          g = gray.at(w - 1 - x, y);
          rho = inverse_depth.at(w - 1 - x, y);
          break;
        case Variation::kBlurred: {
          float sum = 0.f;
          int n = 0;
          for (int dy = -kBlurRadius; dy <= kBlurRadius; ++dy) {
            for (int dx = -kBlurRadius; dx <= kBlurRadius; ++dx) {
              const int xx = x + dx, yy = y + dy;
              if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
              sum += gray.at(xx, yy);
              ++n;
            }
          }
          g = sum / static_cast<float>(n);
          break;
        }
        case Variation::kNearer: {
          const float sx = (static_cast<float>(x) - 0.5f * w) / kZoom + 0.5f * w;
          const float sy = (static_cast<float>(y) - 0.5f * h) / kZoom + 0.5f * h;
          g = sample_bilinear(gray, std::min(sx, w - 1.001f), std::min(sy, h - 1.001f));
          // Nearer by the zoom: inverse depth grows with it (the nearest sample, not blended
          // across depth edges).
          rho = kZoom * inverse_depth.at(static_cast<int>(sx + 0.5f), static_cast<int>(sy + 0.5f));
          break;
        }
        case Variation::kDimNoisy:
          state = state * 1664525u + 1013904223u;
          g = 0.6f * g + 0.1f +
              (static_cast<float>(state >> 8) / 16777216.f - 0.5f) * (8.f / 255.f);
          break;
      }
      out_gray->at(x, y) = g;
      out_inverse_depth->at(x, y) = rho;
    }
  }
}

bool parse_whole(const char* text, int lo, int hi, int* out) {
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || errno != 0 || v < lo || v > hi) return false;
  *out = static_cast<int>(v);
  return true;
}

// The descriptors of every `every`-th frame of one sequence (and of its variations), one image
// per entry.
Status collect(const char* sequence, const Params& p, int every, bool augment,
               std::vector<std::vector<Descriptor>>* images) {
  FrontendFrames frames;
  RGBDTAM_RETURN_IF_ERROR(frames.open(sequence, p));
  FeatureExtractor extractor;
  FeatureOptions opt;
  opt.max_features = p.loop.features;
  extractor.allocate(p.camera.width_px, p.camera.height_px, opt);
  FixedVector<Feature> features;
  features.reserve_once(opt.max_features);
  ImageF gray, inverse_depth;
  gray.allocate(p.camera.width_px, p.camera.height_px);
  inverse_depth.allocate(p.camera.width_px, p.camera.height_px);
  for (int i = 0; i < frames.count(); i += every) {
    if (!frames.load(i)) continue;
    const FramePyramid& frame = frames.frame();
    for (const Variation v : kVariations) {
      if (!augment && v != Variation::kAsRecorded) break;
      vary(frame.gray(0), frame.inverse_depth(0), v, static_cast<uint32_t>(i), &gray,
           &inverse_depth);
      extractor.extract(gray, inverse_depth, frame.intrinsics(0), &features);
      std::vector<Descriptor> image;
      for (const Feature& feature : features) image.push_back(feature.descriptor);
      if (!image.empty()) images->push_back(std::move(image));
    }
  }
  return Status::ok();
}

int train(const TrainOptions& o) {
  Params p;
  Status s = read_params_file(o.config, &p);
  if (!s.is_ok()) {
    std::fprintf(stderr, "rgbdtam vocabulary train: %s\n", s.message());
    return 1;
  }
  // The vocabulary the config names is not read here, but every map saved with it needs it.
  std::vector<CommandFile> inputs = {{"--config", o.config},
                                     {"loop.vocabulary", p.loop.vocabulary}};
  std::vector<std::string> folders;
  for (const char* sequence : o.sequences) add_sequence_inputs(sequence, &inputs, &folders);
  if (!outputs_are_safe("rgbdtam vocabulary train", {{"--out", o.out}}, inputs, folders)) return 2;
  std::vector<std::vector<Descriptor>> images;
  size_t descriptors = 0;
  for (const char* sequence : o.sequences) {
    if (!s.is_ok()) break;
    const size_t before = images.size();
    s = collect(sequence, p, o.every, o.augment, &images);
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
    std::fprintf(
        stderr,
        "usage: rgbdtam vocabulary train <sequence-dir>... --config <file> --out <file>\n"
        "                                [--every N] [--branching K] [--depth L] [--augment]\n");
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
    } else if (std::strcmp(argv[i], "--augment") == 0) {
      o.augment = true;
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
