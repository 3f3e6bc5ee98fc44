#pragma once
// ORB-like features for place recognition: FAST-9 corners spread over a grid, an orientation
// from the patch's intensity centroid, and a 256-bit binary descriptor of smoothed-intensity
// comparisons turned by that orientation. Single scale: places are revisited from about the
// distance they were seen at (a desk, a room). Only corners with sensor depth are kept, each
// lifted to 3-D in its camera frame. Buffers are sized in allocate(); extract() never allocates.

#include <cstdint>

#include "rgbdtam/core/camera.hpp"
#include "rgbdtam/core/fixed_vector.hpp"
#include "rgbdtam/core/image.hpp"
#include "rgbdtam/core/rigid_alignment.hpp"

namespace rgbdtam {

struct Descriptor {
  uint64_t bits[4] = {};
};

// Corners are looked for this far from the border (the orientation patch's radius and one), so
// an image must be wider and higher than twice it.
constexpr int kFeatureBorderPx = 16;

inline int hamming(const Descriptor& a, const Descriptor& b) {
  return __builtin_popcountll(a.bits[0] ^ b.bits[0]) + __builtin_popcountll(a.bits[1] ^ b.bits[1]) +
         __builtin_popcountll(a.bits[2] ^ b.bits[2]) + __builtin_popcountll(a.bits[3] ^ b.bits[3]);
}

struct Feature {
  Descriptor descriptor;
  float u_px = 0.f, v_px = 0.f;
  float x_m = 0.f, y_m = 0.f, z_m = 0.f;  // in the camera's frame
};

struct FeatureOptions {
  int max_features = 400;
  float fast_threshold = 20.f / 255.f;  // intensity units [0,1]
};

class FeatureExtractor {
 public:
  void allocate(int width, int height, const FeatureOptions& opt);
  // gray: undistorted [0,1]; inverse_depth: same size, 0 where unknown; k: their intrinsics.
  void extract(const ImageF& gray, const ImageF& inverse_depth, const PinholeIntrinsics& k,
               FixedVector<Feature>* out);
  const FeatureOptions& options() const { return opt_; }

 private:
  struct Corner {
    float score;
    int16_t x, y;
  };
  static constexpr int kAngleBins = 30;
  static constexpr int kTests = 256;
  struct Test {
    int8_t x1, y1, x2, y2;
  };
  void detect(const ImageF& gray);
  float orientation(const ImageF& gray, int x, int y) const;
  void describe(int x, int y, float angle_rad, Descriptor* d) const;

  FeatureOptions opt_;
  ImageF smooth_, tmp_, score_;
  Test pattern_[kAngleBins][kTests];
  int16_t circle_extent_[16] = {};  // half-width of the orientation disc per row
  FixedVector<Corner> candidates_;
};

// Each query feature's nearest place feature by Hamming distance, kept when clearly nearer than
// the second nearest (Lowe's ratio) and near enough, as 3-D pairs (a: query, b: place).
// Returns the number of pairs written (at most max_pairs).
int match_features(const FixedVector<Feature>& query, const FixedVector<Feature>& place,
                   PointPair* pairs, int max_pairs);

}  // namespace rgbdtam
