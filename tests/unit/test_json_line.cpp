// --json outputs are valid JSON whatever the values: escaped strings, null for inf and nan.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "json_line.hpp"

namespace rgbdtam {
namespace {

TEST(JsonLine, EscapesStringsAndWritesNonFiniteNumbersAsNull) {
  ::testing::internal::CaptureStdout();
  JsonLine()
      .text("sequence", "my \"best\" run\\1\n")
      .number("ate_rmse_cm", std::numeric_limits<double>::infinity())
      .number("rpe", std::nan(""))
      .number("stamp_s", 12.5, 6)
      .integer("frames", -3)
      .boolean("ate_ok", false)
      .end();
  JsonLine().end();
  EXPECT_EQ(::testing::internal::GetCapturedStdout(),
            "{\"sequence\": \"my \\\"best\\\" run\\\\1\\u000a\", \"ate_rmse_cm\": null, "
            "\"rpe\": null, \"stamp_s\": 12.500000, \"frames\": -3, \"ate_ok\": false}\n{}\n");
}

}  // namespace
}  // namespace rgbdtam
