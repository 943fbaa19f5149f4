#include "format_option.h"

#include <string>

namespace sluice::app {

void add_format_option(CLI::App& cmd, uint16_t& major) {
  cmd.add_option_function<std::string>(
         "--format", [&major](const std::string& v) { major = uint16_t(v[0] - '0'); },
         "Container layout: 3.0 (default: each frame ordered coarse to fine, so a view reads a few large\n"
         "runs, and positions in two parts, so a far view reads their high bits only), 2.0 (coarse to\n"
         "fine, positions whole: for sluice 2.0 builds) or 1.5 (each cell's tiers together, for sluice\n"
         "builds older than 2.0)")
      ->check(CLI::IsMember({"3.0", "2.0", "1.5"}));
}

}  // namespace sluice::app
