#include "rgbdtam/hal/usb_devices.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace rgbdtam {
namespace {
// A sysfs attribute holding 4 hex digits.
bool read_hex(const char* path, uint16_t* value) {
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  char buf[16] = {};
  const ssize_t n = ::read(fd, buf, sizeof(buf) - 1);
  ::close(fd);
  if (n <= 0) return false;
  char* end = nullptr;
  const unsigned long v = std::strtoul(buf, &end, 16);
  if (end == buf || v > 0xFFFF) return false;
  *value = static_cast<uint16_t>(v);
  return true;
}
}  // namespace

bool parse_usb_id(const char* text, UsbId* id) {
  unsigned vendor = 0, product = 0;
  int used = 0;
  if (std::sscanf(text, "%4x:%4x%n", &vendor, &product, &used) != 2 || text[used] != '\0') {
    return false;
  }
  id->vendor = static_cast<uint16_t>(vendor);
  id->product = static_cast<uint16_t>(product);
  return true;
}

Status list_usb_devices(const char* sysfs_root, FixedVector<UsbId>* out) {
  out->clear();
  char dir_path[256];
  std::snprintf(dir_path, sizeof(dir_path), "%s/bus/usb/devices", sysfs_root);
  DIR* dir = ::opendir(dir_path);
  if (dir == nullptr) {
    return Status::error(StatusCode::kNotFound, "%s: no USB bus here (is sysfs mounted?)",
                         dir_path);
  }
  while (const dirent* e = ::readdir(dir)) {
    if (e->d_name[0] == '.') continue;
    char path[640];
    UsbId id;
    int n = std::snprintf(path, sizeof(path), "%s/%s/idVendor", dir_path, e->d_name);
    if (n < 0 || n >= static_cast<int>(sizeof(path)) || !read_hex(path, &id.vendor)) {
      continue;  // interfaces have no ids
    }
    n = std::snprintf(path, sizeof(path), "%s/%s/idProduct", dir_path, e->d_name);
    if (n < 0 || n >= static_cast<int>(sizeof(path)) || !read_hex(path, &id.product)) continue;
    if (!out->push_back(id)) break;
  }
  ::closedir(dir);
  return Status::ok();
}

Status require_usb_device(const char* sysfs_root, const UsbId& wanted, const char* what) {
  FixedVector<UsbId> attached;
  attached.reserve_once(32);
  const Status s = list_usb_devices(sysfs_root, &attached);
  if (!s.is_ok()) {
    return Status::error(StatusCode::kNotFound, "%s %04x:%04x: cannot check (%s)", what,
                         wanted.vendor, wanted.product, s.message());
  }
  char list[200] = "";
  size_t used = 0;
  for (const UsbId& id : attached) {
    if (id.vendor == wanted.vendor && id.product == wanted.product) return Status::ok();
    if (used + 12 < sizeof(list)) {
      used += static_cast<size_t>(std::snprintf(list + used, sizeof(list) - used, "%s%04x:%04x",
                                                used > 0 ? " " : "", id.vendor, id.product));
    }
  }
  return Status::error(StatusCode::kNotFound, "%s %04x:%04x is not attached (attached: %s)", what,
                       wanted.vendor, wanted.product, used > 0 ? list : "none");
}

}  // namespace rgbdtam
