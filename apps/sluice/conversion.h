// import::convert() as the sluice command shows it: the plan, a progress
// bar, notes with the flag that changes them, and errors with what to do.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "sluice/import/convert.h"

namespace sluice::app {

struct ConversionReport {
  bool quiet = false;        // no plan, bar or notes (warnings past the bar still counted)
  size_t max_warnings = 20;  // per-frame warnings shown; the rest counted
};

// The error `sluice` shows for a stopped conversion: what the output holds
// and what to pass next.
[[noreturn]] void rethrow_with_advice(const import::ConvertStopped& stopped);

// Prints a conversion as it goes: its observer() shows the plan, a progress
// bar and the notes, each with the flag that changes it; finish() the bar's
// last line and what was counted rather than shown.
class ConversionPrinter {
 public:
  explicit ConversionPrinter(const ConversionReport& report);
  ~ConversionPrinter();
  import::ConvertObserver observer();
  void finish();

  // Runs `conversion` (given observer(), it converts), then finish(); a
  // stopped conversion comes out as rethrow_with_advice() says it.
  template <class Conversion>
  auto run(Conversion&& conversion) {
    try {
      auto result = conversion(observer());
      finish();
      return result;
    } catch (const import::ConvertStopped& e) {
      finish();
      rethrow_with_advice(e);
    } catch (...) {
      finish();
      throw;
    }
  }

 private:
  class Lines;
  std::unique_ptr<Lines> lines_;
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
