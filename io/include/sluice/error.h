// sluice/error.h: the base of every exception sluice's libraries throw.
//
// Each library throws one type of its own, derived from this one and named
// in its headers: io::Error (naming the file, frame and chunk), and
// runtime::Error, render::Error, desktop::Error, xr::Error. A caller that
// only reports catches sluice::Error. Besides these, only std::bad_alloc
// (memory the system refused) escapes.
#pragma once

#include <stdexcept>
#include <string>

namespace sluice {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace sluice
