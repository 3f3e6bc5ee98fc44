#include "rgbdtam/hal/png_decoder.hpp"

#include "png_hooks.hpp"

#include <csetjmp>
#include <cstring>

#include "rgbdtam/core/image.hpp"

namespace rgbdtam {
namespace {

struct MemoryReader {
  const uint8_t* data;
  size_t size;
  size_t pos;
};

void read_bytes(png_structp png, png_bytep out, size_t n) {
  auto* r = static_cast<MemoryReader*>(png_get_io_ptr(png));
  if (r->size - r->pos < n) png_error(png, "file is truncated");
  std::memcpy(out, r->data + r->pos, n);
  r->pos += n;
}

constexpr size_t kDecoderArenaFixedBytes = 96 * 1024;  // png/info structs, zlib state and window
}  // namespace

void PngDecoder::allocate(int max_width) {
  max_width_ = max_width;
  // libpng keeps two rows of up to 4 channels x 16 bits, plus its fixed state.
  arena_.allocate(kDecoderArenaFixedBytes + 4 * (static_cast<size_t>(max_width) * 8 + 64));
  row_.reset(new uint8_t[static_cast<size_t>(max_width) * 8]);
}

Status PngDecoder::decode_gray8(const uint8_t* png, size_t size, int width, int height,
                                uint8_t* out) {
  return decode(png, size, width, height, 8, out);
}

Status PngDecoder::decode_gray16(const uint8_t* png, size_t size, int width, int height,
                                 uint16_t* out) {
  return decode(png, size, width, height, 16, out);
}

Status PngDecoder::decode(const uint8_t* data, size_t size, int width, int height, int bit_depth,
                          void* out) {
  if (size < 8 || png_sig_cmp(data, 0, 8) != 0) {
    return Status::error(StatusCode::kCorrupt, "not a PNG file");
  }
  arena_.reset();
  png_hooks::ErrorSink sink{};
  MemoryReader reader{data, size, 0};
  png_structp png = png_create_read_struct_2(PNG_LIBPNG_VER_STRING, &sink, png_hooks::on_error,
                                             png_hooks::on_warning, &arena_,
                                             png_hooks::arena_malloc, png_hooks::arena_free);
  if (png == nullptr) return Status::error(StatusCode::kOutOfRange, "PNG arena too small");
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) return Status::error(StatusCode::kOutOfRange, "PNG arena too small");
  if (setjmp(png_jmpbuf(png))) {
    return Status::error(StatusCode::kCorrupt, "corrupt PNG: %s", sink.message);
  }
  png_set_read_fn(png, &reader, read_bytes);
  png_read_info(png, info);
  const int w = static_cast<int>(png_get_image_width(png, info));
  const int h = static_cast<int>(png_get_image_height(png, info));
  const int depth = png_get_bit_depth(png, info);
  const int color = png_get_color_type(png, info);
  if (w != width || h != height) {
    png_destroy_read_struct(&png, &info, nullptr);
    return Status::error(StatusCode::kInvalidArgument, "PNG is %dx%d, expected %dx%d", w, h, width,
                         height);
  }
  if (png_get_interlace_type(png, info) != PNG_INTERLACE_NONE) {
    png_destroy_read_struct(&png, &info, nullptr);
    return Status::error(StatusCode::kInvalidArgument, "interlaced PNGs are not supported");
  }
  int channels = 1;
  if (bit_depth == 16) {
    if (color != PNG_COLOR_TYPE_GRAY || depth != 16) {
      png_destroy_read_struct(&png, &info, nullptr);
      return Status::error(StatusCode::kInvalidArgument,
                           "depth PNG must be 16-bit single channel (got %d-bit, colour type %d)",
                           depth, color);
    }
    png_set_swap(png);  // PNG is big-endian
  } else {
    if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (color == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (depth == 16) png_set_strip_16(png);
    png_set_strip_alpha(png);
    channels = (color & PNG_COLOR_MASK_COLOR) != 0 || color == PNG_COLOR_TYPE_PALETTE ? 3 : 1;
  }
  png_read_update_info(png, info);
  if (png_get_rowbytes(png, info) > static_cast<size_t>(max_width_) * 8) {
    png_destroy_read_struct(&png, &info, nullptr);
    return Status::error(StatusCode::kOutOfRange, "PNG row larger than the row buffer");
  }
  for (int y = 0; y < h; ++y) {
    if (bit_depth == 16) {
      png_read_row(png, reinterpret_cast<png_bytep>(static_cast<uint16_t*>(out) + size_t(y) * w),
                   nullptr);
      continue;
    }
    uint8_t* dst = static_cast<uint8_t*>(out) + static_cast<size_t>(y) * w;
    if (channels == 1) {
      png_read_row(png, dst, nullptr);
      continue;
    }
    png_read_row(png, row_.get(), nullptr);
    rgb_to_gray(row_.get(), dst, w);
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return Status::ok();
}

}  // namespace rgbdtam
