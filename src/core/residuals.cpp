#include "rgbdtam/core/residuals.hpp"

#include <cstdio>
#include <cstring>

namespace rgbdtam {
namespace {
bool parse_photometric(const char* s, size_t n, PhotometricMode* out) {
  if (n == 2 && std::strncmp(s, "PS", 2) == 0) {
    *out = PhotometricMode::kSemiDense;
    return true;
  }
  if (n == 2 && std::strncmp(s, "PD", 2) == 0) {
    *out = PhotometricMode::kDense;
    return true;
  }
  return false;
}

bool parse_geometric(const char* s, size_t n, ResidualConfig* out) {
  size_t i = 0;
  if (n >= 3 && std::strncmp(s, "GID", 3) == 0) {
    out->geometric = GeometricMode::kInverseDepth;
    i = 3;
  } else if (n >= 2 && std::strncmp(s, "GD", 2) == 0) {
    out->geometric = GeometricMode::kDepth;
    i = 2;
  } else {
    return false;
  }
  const char* rest = s + i;
  const size_t m = n - i;
  if (m == 1 && rest[0] == 'S') {
    out->sampling = GeometricSampling::kSemiDense;
  } else if (m == 1 && rest[0] == 'D') {
    out->sampling = GeometricSampling::kSubsampled;
  } else if (m == 2 && std::strncmp(rest, "D*", 2) == 0) {
    out->sampling = GeometricSampling::kDense;
  } else {
    return false;
  }
  return true;
}
}  // namespace

bool ResidualConfig::parse(const char* text, ResidualConfig* out) {
  ResidualConfig c;
  c.photometric = PhotometricMode::kOff;
  c.geometric = GeometricMode::kOff;
  const char* plus = std::strchr(text, '+');
  const size_t len = std::strlen(text);
  if (plus == nullptr) {
    if (!parse_photometric(text, len, &c.photometric) && !parse_geometric(text, len, &c)) {
      return false;
    }
  } else {
    const size_t first = static_cast<size_t>(plus - text);
    if (!parse_photometric(text, first, &c.photometric)) return false;
    if (!parse_geometric(plus + 1, len - first - 1, &c)) return false;
  }
  *out = c;
  return true;
}

void ResidualConfig::name(char* buf, int size) const {
  const char* p = photometric == PhotometricMode::kSemiDense ? "PS"
                  : photometric == PhotometricMode::kDense   ? "PD"
                                                             : "";
  const char* g = geometric == GeometricMode::kInverseDepth ? "GID"
                  : geometric == GeometricMode::kDepth      ? "GD"
                                                            : "";
  const char* s = geometric == GeometricMode::kOff             ? ""
                  : sampling == GeometricSampling::kSemiDense  ? "S"
                  : sampling == GeometricSampling::kSubsampled ? "D"
                                                               : "D*";
  const char* sep = (*p != '\0' && *g != '\0') ? "+" : "";
  std::snprintf(buf, static_cast<size_t>(size), "%s%s%s%s", p, sep, g, s);
}

}  // namespace rgbdtam
