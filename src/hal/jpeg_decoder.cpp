#include "rgbdtam/hal/jpeg_decoder.hpp"

// clang-format off
#include <atomic>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <jpeglib.h>
#include <jerror.h>
// clang-format on

namespace rgbdtam {
namespace {

constexpr size_t kAlign = 16;
constexpr size_t aligned(size_t n) { return (n + kAlign - 1) & ~(kAlign - 1); }

// A block: header | payload | footer (the size again, so the top block is found from the top).
struct BlockHeader {
  size_t size;  // the whole block
  size_t free;
};
constexpr size_t kHeader = aligned(sizeof(BlockHeader));
constexpr size_t kFooter = aligned(sizeof(size_t));

// The arenas of open decoders; a decompressor of ours has its arena as libjpeg's client_data.
// Another libjpeg user's client_data (its own, or never set) is compared with these, never
// dereferenced.
constexpr int kMaxDecoders = 8;
std::atomic<JpegArena*> g_arenas[kMaxDecoders];

JpegArena* arena_of(j_common_ptr cinfo) {
  if (cinfo->client_data == nullptr) return nullptr;
  for (const auto& arena : g_arenas) {
    if (arena.load(std::memory_order_acquire) == cinfo->client_data) {
      return static_cast<JpegArena*>(cinfo->client_data);
    }
  }
  return nullptr;
}

bool register_arena(JpegArena* arena) {
  for (auto& slot : g_arenas) {
    JpegArena* empty = nullptr;
    if (slot.compare_exchange_strong(empty, arena)) return true;
  }
  return false;
}

void unregister_arena(JpegArena* arena) {
  for (auto& slot : g_arenas) {
    JpegArena* mine = arena;
    slot.compare_exchange_strong(mine, nullptr);
  }
}

}  // namespace

void JpegArena::allocate(size_t capacity_bytes) {
  memory_.reset(new uint8_t[capacity_bytes + kAlign]);
  const auto address = reinterpret_cast<uintptr_t>(memory_.get());
  base_ = memory_.get() + (aligned(address) - address);
  capacity_ = capacity_bytes;
  top_ = peak_ = 0;
}

void* JpegArena::get(size_t bytes) {
  const size_t size = kHeader + aligned(bytes) + kFooter;
  if (top_ + size > capacity_) return nullptr;  // libjpeg reports it: out of memory
  auto* header = reinterpret_cast<BlockHeader*>(base_ + top_);
  header->size = size;
  header->free = 0;
  *reinterpret_cast<size_t*>(base_ + top_ + size - kFooter) = size;
  top_ += size;
  if (top_ > peak_) peak_ = top_;
  return base_ + top_ - size + kHeader;
}

void JpegArena::put(void* block) {
  if (block == nullptr) return;
  reinterpret_cast<BlockHeader*>(static_cast<uint8_t*>(block) - kHeader)->free = 1;
  // Free blocks at the top go back; one below a kept block waits until that one goes.
  while (top_ > 0) {
    const size_t size = *reinterpret_cast<size_t*>(base_ + top_ - kFooter);
    const auto* header = reinterpret_cast<const BlockHeader*>(base_ + top_ - size);
    if (!header->free) break;
    top_ -= size;
  }
}

// libjpeg reports errors through error_exit, which must not return: back to decode() by
// longjmp (no object with a destructor lives between the two). Warnings (corrupt data that
// libjpeg decodes around) are kept, and make the frame an error too. Not in an anonymous
// namespace: JpegDecoder::State holds one.
struct JpegError {
  jpeg_error_mgr manager;  // first: libjpeg's pointer to it is a pointer to this
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

namespace {

void on_error(j_common_ptr cinfo) {
  auto* error = reinterpret_cast<JpegError*>(cinfo->err);
  (*error->manager.format_message)(cinfo, error->message);
  std::longjmp(error->jump, 1);
}

void on_message(j_common_ptr cinfo) {
  auto* error = reinterpret_cast<JpegError*>(cinfo->err);
  (*error->manager.format_message)(cinfo, error->message);
}
}  // namespace

struct JpegDecoder::State {
  jpeg_decompress_struct cinfo;
  JpegError error;
  std::unique_ptr<JSAMPROW[]> rows;
  bool created = false;
};

JpegDecoder::JpegDecoder() : state_(new State) {}

JpegDecoder::~JpegDecoder() {
  if (state_->created) jpeg_destroy_decompress(&state_->cinfo);
  unregister_arena(&arena_);
}

Status JpegDecoder::open(int width, int height) {
  if (state_->created) {
    jpeg_destroy_decompress(&state_->cinfo);
    state_->created = false;
  }
  width_ = width;
  height_ = height;
  // Progressive JPEGs keep every coefficient (2 bytes per sample, 3 components); baseline
  // ones, what UVC cameras send, need far less.
  const size_t pixels = static_cast<size_t>(width) * static_cast<size_t>(height);
  arena_.allocate(pixels * 6 + (1u << 20));
  unregister_arena(&arena_);
  if (!register_arena(&arena_)) {
    return Status::error(StatusCode::kOutOfRange, "more than %d JPEG decoders open", kMaxDecoders);
  }
  State& s = *state_;
  s.rows.reset(new JSAMPROW[static_cast<size_t>(height)]);
  s.cinfo.err = jpeg_std_error(&s.error.manager);
  s.error.manager.error_exit = on_error;
  s.error.manager.output_message = on_message;
  s.cinfo.client_data = &arena_;
  if (setjmp(s.error.jump) != 0) {
    return Status::error(StatusCode::kOutOfRange, "libjpeg: %s", s.error.message);
  }
  jpeg_create_decompress(&s.cinfo);
  s.created = true;
  return Status::ok();
}

Status JpegDecoder::decode(const uint8_t* jpeg, size_t bytes, uint8_t* gray) {
  State& s = *state_;
  if (!s.created) return Status::error(StatusCode::kInvalidArgument, "JPEG decoder not open");
  if (bytes == 0) return Status::error(StatusCode::kCorrupt, "empty JPEG frame");
  for (int y = 0; y < height_; ++y) s.rows[y] = gray + static_cast<ptrdiff_t>(y) * width_;
  s.error.message[0] = '\0';
  s.error.manager.num_warnings = 0;
  if (setjmp(s.error.jump) != 0) {
    jpeg_abort_decompress(&s.cinfo);  // frees the image's pool: the arena is back at its top
    return Status::error(StatusCode::kCorrupt, "corrupt JPEG frame: %s", s.error.message);
  }
  jpeg_mem_src(&s.cinfo, jpeg, static_cast<unsigned long>(bytes));
  jpeg_read_header(&s.cinfo, TRUE);
  if (s.cinfo.image_width != static_cast<JDIMENSION>(width_) ||
      s.cinfo.image_height != static_cast<JDIMENSION>(height_)) {
    const unsigned w = s.cinfo.image_width, h = s.cinfo.image_height;
    jpeg_abort_decompress(&s.cinfo);
    return Status::error(StatusCode::kCorrupt, "JPEG frame is %ux%u, not %dx%d", w, h, width_,
                         height_);
  }
  s.cinfo.out_color_space = JCS_GRAYSCALE;  // luma only: the chroma is never decoded
  jpeg_start_decompress(&s.cinfo);
  while (s.cinfo.output_scanline < s.cinfo.output_height) {
    jpeg_read_scanlines(&s.cinfo, s.rows.get() + s.cinfo.output_scanline,
                        s.cinfo.output_height - s.cinfo.output_scanline);
  }
  jpeg_finish_decompress(&s.cinfo);
  if (s.error.manager.num_warnings > 0) {
    return Status::error(StatusCode::kCorrupt, "corrupt JPEG frame: %s", s.error.message);
  }
  ++decoded_;
  return Status::ok();
}

}  // namespace rgbdtam

// libjpeg's memory porting interface (jmemsys.h, not installed): these definitions take the
// place of libjpeg's jmemnobs (malloc) in the link.
extern "C" {
void* jpeg_get_small(j_common_ptr cinfo, size_t bytes) {
  rgbdtam::JpegArena* arena = rgbdtam::arena_of(cinfo);
  return arena != nullptr ? arena->get(bytes) : std::malloc(bytes);
}
void jpeg_free_small(j_common_ptr cinfo, void* block, size_t) {
  rgbdtam::JpegArena* arena = rgbdtam::arena_of(cinfo);
  if (arena != nullptr) {
    arena->put(block);
  } else {
    std::free(block);
  }
}
void* jpeg_get_large(j_common_ptr cinfo, size_t bytes) { return jpeg_get_small(cinfo, bytes); }
void jpeg_free_large(j_common_ptr cinfo, void* block, size_t bytes) {
  jpeg_free_small(cinfo, block, bytes);
}
size_t jpeg_mem_available(j_common_ptr, size_t, size_t max_bytes_needed, size_t) {
  return max_bytes_needed;
}
void jpeg_open_backing_store(j_common_ptr cinfo, void*, long) {
  ERREXIT(cinfo, JERR_NO_BACKING_STORE);
}
long jpeg_mem_init(j_common_ptr) { return 0; }
void jpeg_mem_term(j_common_ptr) {}
}
