#include "frame_errors.h"

#include <cstdio>

namespace sluice::app {

std::string FrameErrors::drain(runtime::Player& player) {
  std::string last;
  while (const auto error = player.pop_error()) {
    last = error->text();
    if (seen_++ < kShown) std::fprintf(stderr, "sluice: frame error: %s\n", last.c_str());
  }
  return last;
}

void FrameErrors::print_unshown() const {
  if (seen_ > kShown) {
    std::fprintf(stderr, "sluice: %llu more frame errors not shown\n", static_cast<unsigned long long>(seen_ - kShown));
  }
}

}  // namespace sluice::app
