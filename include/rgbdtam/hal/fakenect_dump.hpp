#pragma once
// A fakenect dump (libfreenect's `record`: INDEX.txt and one file per frame) checked before
// fakenect plays it. fakenect ends the process on a line naming a file it cannot open or a frame
// without its header line, echoing the line's raw bytes, and reads past a frame shorter than the
// mode; an empty frame or a folder in a frame's place ends playback at once. Each becomes an
// error naming the INDEX line and what is wrong with it.

#include "rgbdtam/core/status.hpp"

namespace rgbdtam {

// dir: the dump's folder. Lines after the first empty one are never played and not checked.
Status check_fakenect_dump(const char* dir);

}  // namespace rgbdtam
