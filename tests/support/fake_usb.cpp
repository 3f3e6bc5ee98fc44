#include "fake_usb.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>

#include "tum_writer.hpp"

namespace rgbdtam::testing {
namespace {
std::string make_dirs(std::string dir, std::initializer_list<const char*> parts) {
  for (const char* part : parts) {
    dir += part;
    ::mkdir(dir.c_str(), 0755);
  }
  return dir;
}
}  // namespace

bool add_usb_device(const std::string& sysfs_root, const std::string& name, const char* vendor,
                    const char* product, int bus, int address) {
  const std::string dir = make_dirs(sysfs_root, {"/bus", "/usb", "/devices"}) + "/" + name;
  ::mkdir(dir.c_str(), 0755);
  if (vendor == nullptr) return true;
  bool ok = write_text(dir + "/idVendor", std::string(vendor) + "\n") &&
            write_text(dir + "/idProduct", std::string(product) + "\n");
  if (bus > 0) {
    ok = ok && write_text(dir + "/busnum", std::to_string(bus) + "\n") &&
         write_text(dir + "/devnum", std::to_string(address) + "\n");
  }
  return ok;
}

std::string add_usbfs_node(const std::string& devfs_root, int bus, int address) {
  char bus_dir[8], node[8];
  std::snprintf(bus_dir, sizeof(bus_dir), "/%03d", bus);
  std::snprintf(node, sizeof(node), "/%03d", address);
  const std::string path = make_dirs(devfs_root, {"/bus", "/usb", bus_dir}) + node;
  return write_text(path, "") ? path : "";
}

bool add_video_node(const std::string& sysfs_root, const std::string& device,
                    const std::string& interface, int number) {
  const std::string target = sysfs_root + "/bus/usb/devices/" + device + "/" + interface;
  ::mkdir(target.c_str(), 0755);
  const std::string node =
      make_dirs(sysfs_root, {"/class", "/video4linux"}) + "/video" + std::to_string(number);
  ::mkdir(node.c_str(), 0755);
  return ::symlink(target.c_str(), (node + "/device").c_str()) == 0;
}

}  // namespace rgbdtam::testing
