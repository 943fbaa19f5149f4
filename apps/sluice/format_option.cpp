#include "format_option.h"

#include <string>

namespace sluice::app {

void add_format_option(CLI::App& cmd, uint16_t& major) {
  cmd.add_option_function<std::string>(
         "--format", [&major](const std::string& v) { major = v == "1.5" ? uint16_t(1) : uint16_t(2); },
         "Container layout: 2.0 (default: each frame ordered coarse to fine, so a view reads a few large\n"
         "runs) or 1.5 (each cell's tiers together, for sluice builds older than 2.0)")
      ->check(CLI::IsMember({"2.0", "1.5"}));
}

}  // namespace sluice::app
