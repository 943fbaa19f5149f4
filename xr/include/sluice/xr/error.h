// sluice/xr/error.h: the one exception type the OpenXR session throw: a
// wrong call or argument, or what the system refused (sluice/error.h).
// Bad input read through io throws io::Error instead (it names the file).
#pragma once

#include "sluice/error.h"

namespace sluice::xr {

class Error : public sluice::Error {
 public:
  using sluice::Error::Error;
};

}  // namespace sluice::xr
