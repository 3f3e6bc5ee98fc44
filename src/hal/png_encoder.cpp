#include "rgbdtam/hal/png_encoder.hpp"

#include <csetjmp>
#include <cstring>

#include "png_hooks.hpp"

namespace rgbdtam {
namespace {
void write_bytes(png_structp png, png_bytep bytes, size_t n) {
  if (!static_cast<PngEncoder*>(png_get_io_ptr(png))->append(bytes, n)) {
    png_error(png, "encoded image larger than the output buffer");
  }
}
void flush_bytes(png_structp) {}

// zlib's deflate state at the default window and memory level (about 256 KB) and libpng's own
// structs and row buffers.
constexpr size_t kEncoderArenaFixedBytes = 384 * 1024;
}  // namespace

void PngEncoder::allocate(int max_width, int max_height) {
  const size_t row = static_cast<size_t>(max_width) * 2 + 1;
  arena_.allocate(kEncoderArenaFixedBytes + 4 * (row + 64));
  // Incompressible data grows by zlib's stored-block overhead only.
  capacity_ = row * static_cast<size_t>(max_height) * 101 / 100 + 64 * 1024;
  out_.reset(new uint8_t[capacity_]);
}

bool PngEncoder::append(const uint8_t* bytes, size_t n) {
  if (capacity_ - size_ < n) return false;
  std::memcpy(out_.get() + size_, bytes, n);
  size_ += n;
  return true;
}

Status PngEncoder::encode_gray8(const uint8_t* pixels, int width, int height) {
  return encode(pixels, width, height, 8);
}

Status PngEncoder::encode_gray16(const uint16_t* pixels, int width, int height) {
  return encode(pixels, width, height, 16);
}

Status PngEncoder::encode(const void* pixels, int width, int height, int bit_depth) {
  arena_.reset();
  size_ = 0;
  png_hooks::ErrorSink sink{};
  png_structp png = png_create_write_struct_2(PNG_LIBPNG_VER_STRING, &sink, png_hooks::on_error,
                                              png_hooks::on_warning, &arena_,
                                              png_hooks::arena_malloc, png_hooks::arena_free);
  if (png == nullptr) return Status::error(StatusCode::kOutOfRange, "PNG arena too small");
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) return Status::error(StatusCode::kOutOfRange, "PNG arena too small");
  if (setjmp(png_jmpbuf(png))) {
    return Status::error(StatusCode::kIoError, "PNG encoding failed: %s", sink.message);
  }
  png_set_write_fn(png, this, write_bytes, flush_bytes);
  png_set_compression_level(png, 1);
  png_set_filter(png, 0, PNG_FILTER_SUB);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height),
               bit_depth, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (bit_depth == 16) png_set_swap(png);  // PNG is big-endian
  const size_t row_bytes = static_cast<size_t>(width) * static_cast<size_t>(bit_depth / 8);
  const auto* base = static_cast<const uint8_t*>(pixels);
  for (int y = 0; y < height; ++y) {
    png_write_row(png, base + static_cast<size_t>(y) * row_bytes);
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return Status::ok();
}

}  // namespace rgbdtam
