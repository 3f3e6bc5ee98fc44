#pragma once
#include <string>

#include "rgbdtam/runtime/params.hpp"

namespace rgbdtam {
// Aligns the views of every `every`-th frame of a sequence pairwise, and against those of
// another (unrelated) sequence, printing one CSV row per alignment.
int view_study(const std::string& sequence, const Params& params, const std::string& other,
               const Params& other_params, int every);
}  // namespace rgbdtam
