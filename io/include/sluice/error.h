// sluice/error.h: every exception sluice's libraries throw.
//
// Each library throws one type of its own, derived from sluice::Error:
// io::Error for bad input (the io and import modules: it names the file,
// frame and chunk, so a user can find the bad bytes), and runtime::Error,
// render::Error (the render and stream modules), desktop::Error and
// xr::Error for a wrong call or argument, or what the system refused. A
// caller that only reports catches sluice::Error. Besides these, only
// std::bad_alloc (memory the system refused) escapes.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace sluice {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

namespace io {

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

}  // namespace io

// A type of its own for each module (a wrong call or argument, or what the
// system refused), so a caller can tell them apart.
namespace runtime { class Error : public sluice::Error { public: using sluice::Error::Error; }; }
namespace render { class Error : public sluice::Error { public: using sluice::Error::Error; }; }
namespace desktop { class Error : public sluice::Error { public: using sluice::Error::Error; }; }
namespace xr { class Error : public sluice::Error { public: using sluice::Error::Error; }; }

}  // namespace sluice
