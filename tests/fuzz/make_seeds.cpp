// Writes one valid frame of each message into a corpus folder for the decoder's fuzzer.
#include <cstdio>
#include <string>

#include "rgbdtam/runtime/mavlink.hpp"

using namespace rgbdtam::mavlink;

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  Encoder enc(1, 197);
  uint8_t wire[kMaxFrameBytes];
  Odometry od;
  od.x = 1.5f;
  od.quality = 80;
  StatusText st;
  st.text[0] = 'k';
  auto write = [&](const char* name, int n) {
    const std::string path = std::string(argv[1]) + "/" + name;
    FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) return false;
    // The first byte chooses the fuzzer's chunk size.
    const uint8_t chunk = 7;
    std::fwrite(&chunk, 1, 1, f);
    std::fwrite(wire, 1, static_cast<size_t>(n), f);
    return std::fclose(f) == 0;
  };
  bool ok = write("heartbeat", enc.encode(Heartbeat{}, wire));
  ok = write("statustext", enc.encode(st, wire)) && ok;
  ok = write("odometry", enc.encode(od, wire)) && ok;
  Timesync ts;
  ts.ts1 = 123456789;
  ok = write("timesync", enc.encode(ts, wire)) && ok;
  return ok ? 0 : 1;
}
