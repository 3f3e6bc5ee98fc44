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
  RGBDTAM_RETURN_IF_ERROR(file_.open(path, buffer_, sizeof(buffer_)));
  std::FILE* f = file_.stream();
  bool ok = std::fputs(
                "ply\nformat binary_little_endian 1.0\n"
                "comment rgbdtam keyframe maps, back-projected, not fused; grey = intensity\n"
                "element vertex ",
                f) >= 0;
  count_offset_ = std::ftell(f);
  ok = ok && std::fprintf(f, "%0*d\n", kCountDigits, 0) > 0 &&
       std::fputs(
           "property float x\nproperty float y\nproperty float z\n"
           "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
           f) >= 0;
  return file_.check(ok);
}

void PlyMapWriter::on_keyframe_map(int64_t, const SE3& T_w_k, const PinholeIntrinsics& k,
                                   const FixedVector<FusedPixel>& pixels) {
  if (!file_.is_open() || !file_.status().is_ok()) return;
  const Eigen::Matrix3f R = T_w_k.rotation().cast<float>();
  const Eigen::Vector3f t = T_w_k.translation().cast<float>();
  const Pinhole pinhole = k.pinhole();
  for (const FusedPixel& p : pixels) {
    Eigen::Vector3f p_k(0.f, 0.f, 1.f / p.rho);
    pinhole.back_project(p.x, p.y, p_k.z(), &p_k.x(), &p_k.y());
    const Eigen::Vector3f p_w = R * p_k + t;
    const uint8_t grey =
        static_cast<uint8_t>(std::min(255.f, std::max(0.f, p.intensity * 255.f + 0.5f)));
    const PlyVertex v{p_w.x(), p_w.y(), p_w.z(), grey, grey, grey};
    if (!file_.check(std::fwrite(&v, sizeof(v), 1, file_.stream()) == 1).is_ok()) return;
    ++points_;
  }
  (void)file_.flush();
}

Status PlyMapWriter::close() {
  if (!file_.is_open()) return file_.status();
  // The header's count is what the file holds, even when a write failed or the run stopped.
  std::FILE* f = file_.stream();
  (void)file_.check(
      std::fflush(f) == 0 && std::fseek(f, count_offset_, SEEK_SET) == 0 &&
      std::fprintf(f, "%0*llu", kCountDigits, static_cast<unsigned long long>(points_)) > 0);
  return file_.commit();
}

}  // namespace rgbdtam
