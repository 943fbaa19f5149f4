// import::convert() as the sluice command shows it: the plan, a progress
// bar, notes with the flag that changes them, and errors with what to do.
#pragma once

#include <cstddef>
#include <string>

#include "sluice/import/convert.h"

namespace sluice::app {

struct ConversionReport {
  bool quiet = false;        // no plan, bar or notes (warnings past the bar still counted)
  size_t max_warnings = 20;  // per-frame warnings shown; the rest counted
};

// How the sluice command reads third-party formats: in worker processes
// that are this executable (main() calls import::run_worker first), or in
// process; `read_timeout` seconds a frame.
import::IsolationPolicy import_isolation(bool in_process, int read_timeout);

// Converts as import::convert() does, printing on stderr. A stop at a bad
// frame (import::ConvertStopped) is rethrown as a std::runtime_error that
// says what the output holds and what to pass next.
import::ConvertSummary convert_and_report(const import::ConvertOptions& options, const std::string& output,
                                          const ConversionReport& report);

}  // namespace sluice::app
