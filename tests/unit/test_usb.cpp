// USB presence from sysfs: attached devices are listed, a board's sensor is found or refused
// with what is attached instead. The tests build a fake sysfs tree.
#include <gtest/gtest.h>

#include <string>

#include "fake_usb.hpp"
#include "rgbdtam/hal/usb_devices.hpp"
#include "test_paths.hpp"

namespace rgbdtam {
namespace {

void add_device(const std::string& root, const std::string& name, const char* vendor,
                const char* product) {
  ASSERT_TRUE(testing::add_usb_device(root, name, vendor, product));
}

TEST(Usb, ListsDevicesAndSkipsInterfaces) {
  const std::string root = testing::make_temp_dir("sysfs");
  add_device(root, "usb1", "1d6b", "0002");  // root hub
  add_device(root, "1-1", "045e", "02ae");   // Kinect camera
  add_device(root, "1-1:1.0", nullptr, nullptr);
  FixedVector<UsbId> devices;
  devices.reserve_once(8);
  ASSERT_TRUE(list_usb_devices(root.c_str(), &devices).is_ok());
  ASSERT_EQ(devices.size(), 2);
  EXPECT_TRUE(require_usb_device(root.c_str(), {0x045e, 0x02ae}, "sensor").is_ok());
}

TEST(Usb, AnAbsentSensorIsRefusedWithWhatIsAttached) {
  const std::string root = testing::make_temp_dir("sysfs_absent");
  add_device(root, "usb1", "1d6b", "0002");
  const Status s = require_usb_device(root.c_str(), {0x045e, 0x02ae}, "board 'pi': sensor");
  ASSERT_FALSE(s.is_ok());
  const std::string m = s.message();
  EXPECT_NE(m.find("board 'pi': sensor 045e:02ae is not attached"), std::string::npos) << m;
  EXPECT_NE(m.find("1d6b:0002"), std::string::npos) << m;
  const Status none = require_usb_device((root + "/missing").c_str(), {1, 2}, "sensor");
  ASSERT_FALSE(none.is_ok());
  EXPECT_NE(std::string(none.message()).find("cannot check"), std::string::npos);
}

TEST(Usb, AResetFindsTheDevicesUsbfsNodeAndReportsWhatTheKernelSaid) {
  const std::string sysfs = testing::make_temp_dir("sysfs_reset");
  const std::string devfs = testing::make_temp_dir("devfs_reset");
  ASSERT_TRUE(testing::add_usb_device(sysfs, "usb1", "1d6b", "0002", 1, 1));
  ASSERT_TRUE(testing::add_usb_device(sysfs, "1-1", "045e", "02ae", 1, 4));
  char node[128] = "";
  // No node in this devfs: the path it looked for is named.
  Status s = reset_usb_device(sysfs.c_str(), devfs.c_str(), {0x045e, 0x02ae}, node, sizeof(node));
  ASSERT_FALSE(s.is_ok());
  EXPECT_EQ(std::string(node), devfs + "/bus/usb/001/004");
  EXPECT_NE(std::string(s.message()).find(devfs + "/bus/usb/001/004"), std::string::npos);
  // A node that is not a USB device refuses the ioctl; the error says it was the reset.
  ASSERT_FALSE(testing::add_usbfs_node(devfs, 1, 4).empty());
  s = reset_usb_device(sysfs.c_str(), devfs.c_str(), {0x045e, 0x02ae}, node, sizeof(node));
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("USB reset:"), std::string::npos) << s.message();
  s = reset_usb_device(sysfs.c_str(), devfs.c_str(), {0x2bc5, 0x0401}, node, sizeof(node));
  ASSERT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("2bc5:0401 is not attached"), std::string::npos);
}

TEST(Usb, IdsParse) {
  UsbId id;
  EXPECT_TRUE(parse_usb_id("045e:02ae", &id));
  EXPECT_EQ(id.vendor, 0x045e);
  EXPECT_EQ(id.product, 0x02ae);
  EXPECT_FALSE(parse_usb_id("045e", &id));
  EXPECT_FALSE(parse_usb_id("045e:02ae:1", &id));
  EXPECT_FALSE(parse_usb_id("kinect", &id));
}

}  // namespace
}  // namespace rgbdtam
