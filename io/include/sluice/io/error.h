// sluice/io/error.h: the one exception type the io module throws (and the
// import module, whose errors are bad input too), a sluice::Error.
//
// Every error names where it happened: the file, and where it applies the
// frame and the chunk, so a user can find the bad bytes or the bad input.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "sluice/error.h"

namespace sluice::io {

struct ErrorLocation {
  std::string file{};                  // path as the user gave it; may be empty
  std::optional<uint64_t> frame{};      // frame number in the file or sequence
  std::optional<uint64_t> chunk{};      // chunk number within the frame
};

class Error : public sluice::Error {
 public:
  Error(ErrorLocation where, const std::string& message);

  const ErrorLocation& where() const noexcept { return where_; }
  // The message without the location prefix.
  const std::string& message() const noexcept { return message_; }

 private:
  ErrorLocation where_;
  std::string message_;
};

// "FILE: frame F, chunk C: " (the parts that are known).
std::string format_location(const ErrorLocation& where);

}  // namespace sluice::io
