#include "sluice/runtime/pipeline.h"

namespace sluice::runtime {

std::string FrameError::text() const { return io::format_location(where) + ": " + message; }

}  // namespace sluice::runtime
