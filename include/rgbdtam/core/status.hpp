#pragma once
// Recoverable errors as values. A Status carries a code and a short, fixed-size message,
// so reporting an error never allocates.

#include <cstdarg>
#include <cstdio>

namespace rgbdtam {

enum class StatusCode {
  kOk = 0,
  kInvalidArgument,  // bad config value, bad command line
  kNotFound,         // missing file
  kCorrupt,          // unreadable or truncated data
  kOutOfRange,       // data larger than the buffers sized at init
  kIoError,
  kEndOfStream,
};

class [[nodiscard]] Status {
 public:
  Status() = default;
  static Status ok() { return Status(); }
  static Status error(StatusCode code, const char* fmt, ...) __attribute__((format(printf, 2, 3))) {
    Status s;
    s.code_ = code;
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(s.message_, sizeof(s.message_), fmt, args);
    va_end(args);
    return s;
  }
  bool is_ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const char* message() const { return message_; }

 private:
  StatusCode code_ = StatusCode::kOk;
  char message_[256] = {0};
};

}  // namespace rgbdtam

#define RGBDTAM_RETURN_IF_ERROR(expr)     \
  do {                                    \
    ::rgbdtam::Status status_ = (expr);   \
    if (!status_.is_ok()) return status_; \
  } while (0)
