#include "rgbdtam/hal/usb_devices.hpp"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace rgbdtam {

bool read_sysfs_number(const char* path, int base, uint16_t* value) {
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  char buf[16] = {};
  const ssize_t n = ::read(fd, buf, sizeof(buf) - 1);
  ::close(fd);
  if (n <= 0) return false;
  char* end = nullptr;
  const unsigned long v = std::strtoul(buf, &end, base);
  if (end == buf || v > 0xFFFF) return false;
  *value = static_cast<uint16_t>(v);
  return true;
}

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

namespace {
// Calls visit(device folder, id) for each attached device until it returns false.
template <typename Visit>
Status for_each_usb_device(const char* sysfs_root, Visit visit) {
  char dir_path[256];
  std::snprintf(dir_path, sizeof(dir_path), "%s/bus/usb/devices", sysfs_root);
  DIR* dir = ::opendir(dir_path);
  if (dir == nullptr) {
    return Status::error(StatusCode::kNotFound, "%s: no USB bus here (is sysfs mounted?)",
                         dir_path);
  }
  while (const dirent* e = ::readdir(dir)) {
    if (e->d_name[0] == '.') continue;
    char device[512], path[640];
    UsbId id;
    std::snprintf(device, sizeof(device), "%s/%s", dir_path, e->d_name);
    std::snprintf(path, sizeof(path), "%s/idVendor", device);
    if (!read_sysfs_number(path, 16, &id.vendor)) continue;  // interfaces have no ids
    std::snprintf(path, sizeof(path), "%s/idProduct", device);
    if (!read_sysfs_number(path, 16, &id.product)) continue;
    if (!visit(device, id)) break;
  }
  ::closedir(dir);
  return Status::ok();
}
}  // namespace

Status list_usb_devices(const char* sysfs_root, FixedVector<UsbId>* out) {
  out->clear();
  return for_each_usb_device(sysfs_root,
                             [&](const char*, const UsbId& id) { return out->push_back(id); });
}

Status reset_usb_device(const char* sysfs_root, const char* devfs_root, const UsbId& id, char* node,
                        size_t node_size) {
  uint16_t bus = 0, address = 0;
  bool found = false;
  RGBDTAM_RETURN_IF_ERROR(for_each_usb_device(sysfs_root, [&](const char* device, const UsbId& d) {
    if (d.vendor != id.vendor || d.product != id.product) return true;
    char path[640];
    std::snprintf(path, sizeof(path), "%s/busnum", device);
    found = read_sysfs_number(path, 10, &bus);
    std::snprintf(path, sizeof(path), "%s/devnum", device);
    found = found && read_sysfs_number(path, 10, &address);
    return !found;
  }));
  if (!found) {
    return Status::error(StatusCode::kNotFound, "USB %04x:%04x is not attached", id.vendor,
                         id.product);
  }
  std::snprintf(node, node_size, "%s/bus/usb/%03u/%03u", devfs_root, bus, address);
  const int fd = ::open(node, O_WRONLY | O_CLOEXEC);
  if (fd < 0) return Status::error(StatusCode::kIoError, "%s: %s", node, std::strerror(errno));
  const int r = ::ioctl(fd, USBDEVFS_RESET, 0);
  const int error = errno;
  ::close(fd);
  if (r < 0) {
    return Status::error(StatusCode::kIoError, "%s: USB reset: %s", node, std::strerror(error));
  }
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
