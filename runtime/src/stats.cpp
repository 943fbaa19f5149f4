#include "sluice/runtime/stats.h"

#include <algorithm>

namespace sluice::runtime {
namespace {

double per_second(double amount, double seconds) { return seconds > 0 ? amount / seconds : 0; }

}  // namespace

PipelineRates rates_between(const PipelineStats& before, const PipelineStats& after) {
  PipelineRates r;
  r.seconds = after.elapsed_seconds - before.elapsed_seconds;
  r.frames_per_second = per_second(double(after.frames_delivered - before.frames_delivered), r.seconds);
  const double read = double(after.bytes_read - before.bytes_read) / 1e6;
  r.read_mbps = per_second(read, r.seconds);
  r.read_busy_mbps = per_second(read, after.read_seconds - before.read_seconds);
  r.decode_mbps = per_second(double(after.decoded_bytes - before.decoded_bytes) / 1e6, r.seconds);
  for (const WorkerStats& a : after.workers) {
    const auto same = std::find_if(before.workers.begin(), before.workers.end(),
                                   [&](const WorkerStats& w) { return w.slot == a.slot; });
    const WorkerStats b = same != before.workers.end() ? *same : WorkerStats{a.slot};
    const double busy = a.busy_seconds - b.busy_seconds;
    r.worker_decode_mbps.push_back(per_second(double(a.output_bytes - b.output_bytes) / 1e6, busy));
    r.worker_busy.push_back(std::clamp(per_second(busy, r.seconds), 0.0, 1.0));
  }
  return r;
}

}  // namespace sluice::runtime
