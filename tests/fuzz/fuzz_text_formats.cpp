// libFuzzer target for every text format the programs read: TUM lists (rgb.txt, depth.txt),
// configs, boards and trajectories (eval's reader). The first byte chooses the format; the
// rest is the file. Each must parse or fail with a status, never crash or overrun.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rgbdtam/hal/tum_replay_source.hpp"
#include "rgbdtam/hal/tum_trajectory.hpp"
#include "rgbdtam/runtime/board.hpp"
#include "rgbdtam/runtime/params.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  // The readers take NUL-terminated text (read_text_file refuses a NUL inside).
  std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  text = text.substr(0, text.find('\0'));
  switch (data[0] % 5) {
    case 0: {
      rgbdtam::TumList list;
      (void)rgbdtam::parse_tum_list(text.c_str(), "rgb.txt", &list);
      break;
    }
    case 1: {
      rgbdtam::Params params;
      if (rgbdtam::parse_params(text.c_str(), "fuzz.conf", &params).is_ok()) {
        static char printed[1 << 16];
        rgbdtam::print_params(params, printed, sizeof(printed));
      }
      break;
    }
    case 2: {
      rgbdtam::Board board;
      if (rgbdtam::parse_board(text.c_str(), "board.conf", "board/fuzz", &board).is_ok()) {
        (void)rgbdtam::validate_board(board);
      }
      break;
    }
    case 3: {
      std::vector<rgbdtam::StampedPose> poses;
      int bad = 0;
      (void)rgbdtam::parse_tum_trajectory(&text[0], &poses, &bad);
      break;
    }
    default: {
      rgbdtam::Params params;
      (void)rgbdtam::set_param(text.c_str(), "--set", &params);
      rgbdtam::Board board;
      (void)rgbdtam::set_board_value(text.c_str(), &board);
      break;
    }
  }
  return 0;
}
