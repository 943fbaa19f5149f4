// sluice/runtime/frame_error.h: a frame that could not be delivered.
#pragma once

#include <string>

#include "sluice/io/error.h"

namespace sluice::runtime {

// Why a frame failed: a read error or a file that ends early, a corrupt frame
// header, a corrupt chunk, or no memory for its buffers. `where` names the
// file and frame, and the chunk when one chunk was bad.
struct FrameError {
  io::ErrorLocation where;
  std::string message;  // what went wrong, without the location

  // "FILE: frame F, chunk C: message"
  std::string text() const;
  static FrameError from(const io::Error& e) { return {e.where(), e.message()}; }
};

}  // namespace sluice::runtime
