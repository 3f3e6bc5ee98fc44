#include "rgbdtam/hal/v4l2_nodes.hpp"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <linux/videodev2.h>
#include <unistd.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace rgbdtam {
namespace {

// The node's USB interface (resolved) and its device's id; false when the node is no USB
// device's (a platform camera) or the path is too long to keep.
bool usb_interface_of(const char* sysfs_root, int number, char* interface, size_t size, UsbId* id) {
  char path[PATH_MAX + 16], resolved[PATH_MAX];
  std::snprintf(path, sizeof(path), "%s/class/video4linux/video%d/device", sysfs_root, number);
  if (::realpath(path, resolved) == nullptr || std::strlen(resolved) >= size) return false;
  std::memcpy(interface, resolved, std::strlen(resolved) + 1);
  // The interface's parent folder is the USB device.
  std::snprintf(path, sizeof(path), "%s/../idVendor", resolved);
  if (!read_sysfs_number(path, 16, &id->vendor)) return false;
  std::snprintf(path, sizeof(path), "%s/../idProduct", resolved);
  return read_sysfs_number(path, 16, &id->product);
}

// Appends to a bounded message, truncating.
void append(char* out, size_t size, size_t* used, const char* format, ...) {
  if (*used + 1 >= size) return;
  va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(out + *used, size - *used, format, args);
  va_end(args);
  if (n > 0) *used = std::min(size - 1, *used + static_cast<size_t>(n));
}

}  // namespace

bool V4l2NodeFinder::Node::offers(uint32_t fourcc) const {
  return std::find(formats, formats + format_count, fourcc) != formats + format_count;
}
bool V4l2NodeFinder::Node::capture() const { return (caps & V4L2_CAP_VIDEO_CAPTURE) != 0; }
bool V4l2NodeFinder::Node::metadata() const { return (caps & V4L2_CAP_META_CAPTURE) != 0; }

bool V4l2NodeFinder::query(V4l2Io* io, const char* devfs_root, Node* node) const {
  char path[V4l2Nodes::kPathBytes];
  std::snprintf(path, sizeof(path), "%s/video%d", devfs_root, node->number);
  const int fd = io->open(path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  v4l2_capability cap{};
  const bool asked = io->ioctl(fd, VIDIOC_QUERYCAP, &cap) == 0;
  node->caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  for (uint32_t i = 0; asked && node->capture() && node->format_count < kMaxFormats; ++i) {
    v4l2_fmtdesc f{};
    f.index = i;
    f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (io->ioctl(fd, VIDIOC_ENUM_FMT, &f) < 0) break;
    node->formats[node->format_count++] = f.pixelformat;
  }
  (void)io->close(fd);
  return asked;
}

void V4l2NodeFinder::describe(char* out, size_t size) const {
  size_t used = 0;
  out[0] = '\0';
  for (int i = 0; i < count_; ++i) {
    append(out, size, &used, "%svideo%d", i > 0 ? ", " : "", nodes_[i].number);
    if (nodes_[i].metadata()) append(out, size, &used, " metadata");
    for (int f = 0; f < nodes_[i].format_count; ++f) {
      char text[5];
      v4l2_fourcc_text(nodes_[i].formats[f], text);
      for (int c = 3; c > 0 && text[c] == ' '; --c) text[c] = '\0';  // "Z16 " reads "Z16"
      append(out, size, &used, " %s", text);
    }
  }
}

void V4l2NodeFinder::metadata_of(const Node& video, const char* devfs_root, char* out) const {
  for (int i = 0; i < count_; ++i) {
    if (nodes_[i].metadata() && std::strcmp(nodes_[i].interface, video.interface) == 0) {
      std::snprintf(out, V4l2Nodes::kPathBytes, "%s/video%d", devfs_root, nodes_[i].number);
      return;
    }
  }
}

Status V4l2NodeFinder::find(V4l2Io* io, const char* sysfs_root, const char* devfs_root,
                            const UsbId& usb, uint32_t colour_fourcc, V4l2Nodes* out) {
  *out = V4l2Nodes();
  count_ = 0;
  char class_dir[PATH_MAX];
  std::snprintf(class_dir, sizeof(class_dir), "%s/class/video4linux", sysfs_root);
  // No such folder: no V4L2 driver has made a node yet, the same as none of the camera's.
  DIR* dir = ::opendir(class_dir);
  while (const dirent* e = dir != nullptr ? ::readdir(dir) : nullptr) {
    int number = -1;
    char rest = 0;
    if (count_ == kMaxNodes || std::sscanf(e->d_name, "video%d%c", &number, &rest) != 1) continue;
    Node& n = nodes_[count_];
    n = Node();
    n.number = number;
    UsbId id;
    if (!usb_interface_of(sysfs_root, number, n.interface, sizeof(n.interface), &id)) continue;
    if (id.vendor == usb.vendor && id.product == usb.product && query(io, devfs_root, &n)) {
      ++count_;
    }
  }
  if (dir != nullptr) ::closedir(dir);
  if (count_ == 0) {
    // Not attached (the board's start-up check lists what is), being re-enumerated after a
    // reset, or attached without its driver.
    return Status::error(StatusCode::kNotFound,
                         "USB %04x:%04x has no video node (not attached, or uvcvideo not bound)",
                         usb.vendor, usb.product);
  }
  // In the order the kernel numbered them.
  std::sort(nodes_, nodes_ + count_,
            [](const Node& a, const Node& b) { return a.number < b.number; });
  const Node* depth = nullptr;
  const Node* colour = nullptr;
  for (int i = 0; i < count_; ++i) {
    const Node& n = nodes_[i];
    if (!n.capture()) continue;
    if (depth == nullptr && n.offers(V4L2_PIX_FMT_Z16)) depth = &n;
    if (colour == nullptr && n.offers(colour_fourcc) && !n.offers(V4L2_PIX_FMT_Z16)) colour = &n;
  }
  if (depth == nullptr || colour == nullptr) {
    char list[512], wanted[5];
    describe(list, sizeof(list));
    v4l2_fourcc_text(colour_fourcc, wanted);
    return Status::error(StatusCode::kNotFound, "USB %04x:%04x has no %s node (its nodes: %s)",
                         usb.vendor, usb.product, depth == nullptr ? "Z16 depth" : wanted, list);
  }
  std::snprintf(out->depth, sizeof(out->depth), "%s/video%d", devfs_root, depth->number);
  std::snprintf(out->colour, sizeof(out->colour), "%s/video%d", devfs_root, colour->number);
  metadata_of(*depth, devfs_root, out->depth_metadata);
  metadata_of(*colour, devfs_root, out->colour_metadata);
  return Status::ok();
}

}  // namespace rgbdtam
