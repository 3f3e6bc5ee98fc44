#pragma once
// The operator's messages' length, shared by the message types and the MAVLink codec (which
// needs nothing else of the project and builds alone, as the fuzzers build it).

namespace rgbdtam {

// The longest status text sent: a prefix and a whole error message (Status holds 255), in
// 50-character STATUSTEXT chunks that MAVLink 2 joins by `id` and `chunk_seq`.
constexpr int kMaxStatusTextChars = 300;

}  // namespace rgbdtam
