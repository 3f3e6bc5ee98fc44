#pragma once
// A fake sysfs USB tree (root/bus/usb/devices/<name>/{idVendor,idProduct,busnum,devnum}), laid
// out as the kernel does, and a fake devfs holding the device's usbfs node as a plain file
// (on which the reset ioctl fails, as it does for a node that is not a USB device).
#include <string>

namespace rgbdtam::testing {

// vendor == nullptr: an interface (no ids). bus/address 0: no busnum/devnum files.
bool add_usb_device(const std::string& sysfs_root, const std::string& name, const char* vendor,
                    const char* product, int bus = 0, int address = 0);
// devfs_root/bus/usb/BBB/DDD as a regular file; returns its path ("" on failure).
std::string add_usbfs_node(const std::string& devfs_root, int bus, int address);
// A video node of USB device `device` (made by add_usb_device), on its interface `interface`
// ("1-2:1.0"): root/class/video4linux/video<number>/device links to the interface's folder,
// as the kernel links it.
bool add_video_node(const std::string& sysfs_root, const std::string& device,
                    const std::string& interface, int number);

}  // namespace rgbdtam::testing
