// sluice/runtime/error.h: the one exception type the streaming pipeline, the player and the memory budget throw: a
// wrong call or argument, or what the system refused (sluice/error.h).
// Bad input read through io throws io::Error instead (it names the file).
#pragma once

#include "sluice/error.h"

namespace sluice::runtime {

class Error : public sluice::Error {
 public:
  using sluice::Error::Error;
};

}  // namespace sluice::runtime
