// A value or a human-readable reason there is none: the error channel of the host tools.
//
// The host tools never throw across their API. Every fallible function returns an
// Outcome<T>; on failure error() is a complete sentence that names the file (and the line, for
// text formats) and what is wrong, ready to print as is. This is the host-side counterpart of
// seqslam::Result<T>, which carries only a status code because the core has no strings.
#pragma once

#include <string>
#include <utility>

namespace seqslam::tools {

// The failure half of an Outcome: `return Error{path + ": file is empty"};`.
struct Error {
  std::string message;
};

template <typename T>
class [[nodiscard]] Outcome {
 public:
  Outcome(T value) : ok_(true), value_(std::move(value)) {}  // NOLINT: implicit by design
  Outcome(Error error) : ok_(false), error_(std::move(error.message)) {  // NOLINT: implicit
    if (error_.empty()) error_ = "unknown error";
  }

  bool ok() const noexcept { return ok_; }
  explicit operator bool() const noexcept { return ok_; }

  // Only meaningful when ok(); otherwise a default-constructed T.
  const T& value() const& noexcept { return value_; }
  T& value() & noexcept { return value_; }
  T&& value() && noexcept { return std::move(value_); }

  // Empty when ok(); otherwise a non-empty message.
  const std::string& error() const noexcept { return error_; }

 private:
  bool ok_;
  T value_{};
  std::string error_;
};

}  // namespace seqslam::tools
