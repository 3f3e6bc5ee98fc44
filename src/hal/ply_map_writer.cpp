#include "rgbdtam/hal/ply_map_writer.hpp"

#include <cerrno>
#include <cstring>

namespace rgbdtam {
namespace {
constexpr int kCountDigits = 10;

#pragma pack(push, 1)
struct PlyVertex {
  float x, y, z;
  uint8_t r, g, b;
};
#pragma pack(pop)
static_assert(sizeof(PlyVertex) == 15, "PLY vertex must be packed");
}  // namespace

PlyMapWriter::~PlyMapWriter() { (void)close(); }

Status PlyMapWriter::open(const char* path) {
  file_ = std::fopen(path, "wb");
  if (file_ == nullptr) {
    return Status::error(StatusCode::kIoError, "%s: %s", path, std::strerror(errno));
  }
  std::setvbuf(file_, buffer_, _IOFBF, sizeof(buffer_));
  std::fputs(
      "ply\nformat binary_little_endian 1.0\n"
      "comment rgbdtam keyframe maps, back-projected, not fused; grey = intensity\n"
      "element vertex ",
      file_);
  count_offset_ = std::ftell(file_);
  std::fprintf(file_, "%0*d\n", kCountDigits, 0);
  std::fputs(
      "property float x\nproperty float y\nproperty float z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
      file_);
  return Status::ok();
}

void PlyMapWriter::on_keyframe_map(int64_t, const SE3& T_w_k, const PinholeIntrinsics& k,
                                   const FixedVector<FusedPixel>& pixels) {
  if (file_ == nullptr) return;
  const Eigen::Matrix3f R = T_w_k.rotation().cast<float>();
  const Eigen::Vector3f t = T_w_k.translation().cast<float>();
  for (const FusedPixel& p : pixels) {
    const float z = 1.f / p.rho;
    const Eigen::Vector3f p_k((p.x - static_cast<float>(k.cx_px)) / static_cast<float>(k.fx_px) * z,
                              (p.y - static_cast<float>(k.cy_px)) / static_cast<float>(k.fy_px) * z,
                              z);
    const Eigen::Vector3f p_w = R * p_k + t;
    const uint8_t grey =
        static_cast<uint8_t>(std::min(255.f, std::max(0.f, p.intensity * 255.f + 0.5f)));
    const PlyVertex v{p_w.x(), p_w.y(), p_w.z(), grey, grey, grey};
    if (std::fwrite(&v, sizeof(v), 1, file_) != 1) write_failed_ = true;
    ++points_;
  }
}

Status PlyMapWriter::close() {
  if (file_ == nullptr) return Status::ok();
  bool ok =
      !write_failed_ && std::fseek(file_, count_offset_, SEEK_SET) == 0 &&
      std::fprintf(file_, "%0*llu", kCountDigits, static_cast<unsigned long long>(points_)) > 0;
  ok = (std::fclose(file_) == 0) && ok;
  file_ = nullptr;
  return ok ? Status::ok() : Status::error(StatusCode::kIoError, "map PLY write failed");
}

}  // namespace rgbdtam
