#pragma once
// A UVC depth camera's video nodes, found by the camera's USB id and by what each node offers,
// not by number: /dev/videoN numbers follow the order devices enumerate in, and a RealSense
// D4xx or an Orbbec Gemini presents up to six nodes (depth, infrared, colour, and after each a
// metadata node). The kernel's sysfs says which USB device a node belongs to
// (<sysfs>/class/video4linux/videoN/device is its USB interface, whose parent holds idVendor
// and idProduct); VIDIOC_QUERYCAP and VIDIOC_ENUM_FMT say what it offers.

#include <cstddef>
#include <cstdint>

#include "rgbdtam/core/status.hpp"
#include "rgbdtam/hal/usb_devices.hpp"
#include "rgbdtam/hal/v4l2_io.hpp"

namespace rgbdtam {

struct V4l2Nodes {
  static constexpr int kPathBytes = 96;
  char depth[kPathBytes] = "";   // the capture node offering Z16
  char colour[kPathBytes] = "";  // the capture node offering the colour format, without Z16
  // uvcvideo's metadata node of the same USB interface as each ("" when the kernel has none).
  char depth_metadata[kPathBytes] = "";
  char colour_metadata[kPathBytes] = "";
};

// Searches <sysfs_root>/class/video4linux for the nodes of the USB device `usb`, opened as
// <devfs_root>/videoN through io; the lowest-numbered node that fits each role is taken. An
// error names what the device's nodes offer when none fits. Holds its scratch, so a reopen after a
// USB reset (which may renumber the nodes) finds them again without allocating.
class V4l2NodeFinder {
 public:
  Status find(V4l2Io* io, const char* sysfs_root, const char* devfs_root, const UsbId& usb,
              uint32_t colour_fourcc, V4l2Nodes* out);

 private:
  static constexpr int kMaxNodes = 32;  // video nodes looked at
  static constexpr int kMaxFormats = 16;
  struct Node {
    int number = -1;
    char interface[256] = "";  // the USB interface's sysfs folder, resolved
    uint32_t caps = 0;
    uint32_t formats[kMaxFormats] = {};
    int format_count = 0;
    bool offers(uint32_t fourcc) const;
    bool capture() const;
    bool metadata() const;
  };
  bool query(V4l2Io* io, const char* devfs_root, Node* node) const;
  void describe(char* out, size_t size) const;
  void metadata_of(const Node& video, const char* devfs_root, char* out) const;
  Node nodes_[kMaxNodes];
  int count_ = 0;
};

}  // namespace rgbdtam
