// The frame errors a player reports while it plays, printed to stderr: the
// first 20 (a damaged file can fail every frame), and at the end how many
// more there were.
#pragma once

#include <cstdint>
#include <string>

#include "sluice/runtime/player.h"

namespace sluice::app {

class FrameErrors {
 public:
  // Prints the errors `player` has queued (up to the limit); returns the
  // last one's text, empty when none was queued.
  std::string drain(runtime::Player& player);
  // "N more frame errors not shown", when there were.
  void print_unshown() const;

 private:
  static constexpr uint64_t kShown = 20;
  uint64_t seen_ = 0;
};

}  // namespace sluice::app
