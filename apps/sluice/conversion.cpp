// The sluice command's view of a conversion: import::convert()'s plan,
// progress and notes on stderr, each note with the flag that changes it.
#include "conversion.h"

#include <cstdio>
#include <memory>
#include <stdexcept>

#include "progress.h"

namespace sluice::app {
namespace {

// The flag that changes what a note is about ("" when none).
const char* advice(import::Notice about) {
  switch (about) {
    case import::Notice::NoTimes: return " Pass --dt SECONDS (time between frames) or --fps N to give them times.";
    case import::Notice::NoIds: return "\n         Pass --id-array NAME if the ids have another name.";
    case import::Notice::RepeatedIds: return " (pass --id-array NAME for another array)";
    case import::Notice::NoSpacing: return "\n         Pass --spacing to give it.";
    case import::Notice::FarParticles: return " (--drop-outliers DIST leaves such particles out)";
    case import::Notice::Up: return ". Pass --up to choose.";
    default: return "";
  }
}

bool per_frame_warning(import::Notice about) {
  return about == import::Notice::Repair || about == import::Notice::FarParticles;
}

bool is_warning(import::Notice about) {
  switch (about) {
    case import::Notice::TimesGiven:
    case import::Notice::NoTimes:
    case import::Notice::SpacingLater:
    case import::Notice::Up:
    case import::Notice::UpGiven:
    case import::Notice::Skipped: return false;
    default: return true;
  }
}

}  // namespace

class ConversionPrinter::Lines {
 public:
  explicit Lines(const ConversionReport& r) : report_(r) {}

  void planned(const import::ConvertPlan& p) {
    if (!report_.quiet) {
      const io::FileHeader& h = p.header;
      std::fprintf(stderr, "converting %s\n  %llu frames, spacing %g (%s), radius %g, %s positions, LOD from %s\n",
                   p.source.description.c_str(), (unsigned long long)p.frames, h.particle_spacing,
                   p.spacing_given ? "given" : "estimated", h.particle_radius,
                   h.position_coding == io::PositionCoding::Float32 ? "float32 (lossless)" : "16-bit quantized",
                   h.lod_id_array.empty() ? "particle order" : ("id array '" + h.lod_id_array + "'").c_str());
    }
    bar_ = std::make_unique<ProgressBar>("frames", p.frames, report_.quiet);
  }

  void progressed(const import::ConvertProgress& p) {
    bar_->update(p.frames_done, p.input_bytes, p.output_bytes);
    if (p.frames_done == p.frames) finish_bar();  // the closing notes print under the finished bar
  }

  void noted(const import::Note& n) {
    const std::string line = n.text + advice(n.about);
    if (n.about == import::Notice::Skipped) {
      skipped_.push_back(n.text);
      return;
    }
    if (per_frame_warning(n.about)) {
      if (shown_++ < report_.max_warnings) print("warning: " + line);
      else ++suppressed_;
      return;
    }
    if (!report_.quiet) print((is_warning(n.about) ? "warning: " : n.about == import::Notice::Up || n.about == import::Notice::UpGiven ? "" : "note: ") + line);
  }

  // The bar's last line, then what was counted rather than shown.
  void finish() {
    finish_bar();
    if (suppressed_) std::fprintf(stderr, "warning: %zu more warnings not shown\n", suppressed_);
    if (skipped_.empty()) return;
    std::fprintf(stderr, "skipped %zu frame%s that could not be read:\n", skipped_.size(), skipped_.size() == 1 ? "" : "s");
    for (const std::string& s : skipped_) std::fprintf(stderr, "  %s\n", s.c_str());
  }

 private:
  void finish_bar() {
    if (bar_ && !bar_finished_) bar_->finish();
    bar_finished_ = true;
  }

  void print(const std::string& line) {
    if (bar_ && !bar_finished_) bar_->print(line);
    else std::fprintf(stderr, "%s\n", line.c_str());
  }

  ConversionReport report_;
  std::unique_ptr<ProgressBar> bar_;
  bool bar_finished_ = false;
  size_t shown_ = 0, suppressed_ = 0;
  std::vector<std::string> skipped_;
};

ConversionPrinter::ConversionPrinter(const ConversionReport& report) : lines_(std::make_unique<Lines>(report)) {}
ConversionPrinter::~ConversionPrinter() = default;

import::ConvertObserver ConversionPrinter::observer() {
  import::ConvertObserver observer;
  Lines* lines = lines_.get();
  observer.planned = [lines](const import::ConvertPlan& p) { lines->planned(p); };
  observer.progressed = [lines](const import::ConvertProgress& p) { lines->progressed(p); };
  observer.noted = [lines](const import::Note& n) { lines->noted(n); };
  return observer;
}

void ConversionPrinter::finish() { lines_->finish(); }

void rethrow_with_advice(const import::ConvertStopped& e) {
  const uint64_t kept = e.frames_kept();
  if (!e.output_complete()) {  // writing failed (disk full?): nothing was renamed into place
    throw std::runtime_error(std::string(e.what()) + "\n  " + e.output() + " holds the " + std::to_string(kept) +
                             " frames written before; `sluice recover` rebuilds a file of them once there is room");
  }
  throw std::runtime_error(std::string(e.what()) + "\n  " + e.output() + " holds the " + std::to_string(kept) + " frame" +
                           (kept == 1 ? "" : "s") + " before it; pass --skip-bad to leave bad frames out and convert the rest");
}

import::IsolationPolicy import_isolation(bool in_process, int read_timeout) {
  import::IsolationPolicy policy;
  policy.mode = in_process ? import::Isolation::InProcess : import::Isolation::WorkerProcesses;
  policy.worker = "/proc/self/exe";
  policy.read_limit = std::chrono::seconds(read_timeout);
  return policy;
}

import::ConvertSummary convert_and_report(const import::ConvertOptions& options, const std::string& output,
                                          const ConversionReport& report) {
  ConversionPrinter printer(report);
  return printer.run([&](const import::ConvertObserver& observer) { return import::convert(options, output, observer); });
}

}  // namespace sluice::app
