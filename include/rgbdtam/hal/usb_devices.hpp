#pragma once
// USB presence of the board's sensor, read from sysfs (<root>/bus/usb/devices/*/idVendor and
// idProduct), which needs no library and links statically. A board that declares its sensor's
// USB id is refused at start-up when no such device is attached, with what is attached.

#include <cstddef>
#include <cstdint>

#include "rgbdtam/core/fixed_vector.hpp"
#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

struct UsbId {
  uint16_t vendor = 0;
  uint16_t product = 0;
};

// A sysfs attribute holding one number in the given base (idVendor: 16, busnum: 10); false
// when it is missing or not such a number.
bool read_sysfs_number(const char* path, int base, uint16_t* value);

// Parses "vvvv:pppp" (hex); false when malformed.
bool parse_usb_id(const char* text, UsbId* id);

// The attached devices (at most `out`'s capacity); sysfs_root is "/sys" on a board.
Status list_usb_devices(const char* sysfs_root, FixedVector<UsbId>* out);

// Resets the attached device `id` through usbfs (<devfs_root>/bus/usb/BBB/DDD, USBDEVFS_RESET,
// the ioctl libusb_reset_device issues; done directly so the static firmware needs no libusb).
// The kernel re-enumerates it and rebinds its drivers; node receives the usbfs path tried.
Status reset_usb_device(const char* sysfs_root, const char* devfs_root, const UsbId& id, char* node,
                        size_t node_size);

// Ok when `wanted` is attached; else an error naming it and listing what is attached.
Status require_usb_device(const char* sysfs_root, const UsbId& wanted, const char* what);

}  // namespace rgbdtam
