#pragma once
// Residual configurations of the paper's ablation table (PS, PD, GIDS, GIDD, GIDD*, PS+GIDD,
// PS+GDD, ...): a photometric part and a geometric part, each optional.

namespace rgbdtam {

enum class PhotometricMode { kOff, kSemiDense, kDense };
enum class GeometricMode { kOff, kInverseDepth, kDepth };
enum class GeometricSampling { kSemiDense, kSubsampled, kDense };

struct ResidualConfig {
  PhotometricMode photometric = PhotometricMode::kSemiDense;
  GeometricMode geometric = GeometricMode::kInverseDepth;
  GeometricSampling sampling = GeometricSampling::kSubsampled;

  // Parses "PS", "PD", "GIDS", "GIDD", "GIDD*", "GDS", "GDD", "GDD*" or "P?+G??" pairs.
  static bool parse(const char* text, ResidualConfig* out);
  // Writes the canonical name; buf needs 16 bytes.
  void name(char* buf, int size) const;
};

}  // namespace rgbdtam
