#include "reads_text.h"

#include <cstdio>

namespace sluice::app {

std::string reads_text(const runtime::PipelineStats& s) {
  if (s.frames_read == 0) return "nothing read yet";
  char text[160];
  const double per = double(s.bytes_read) / double(s.frames_read);
  const double share = s.record_bytes > 0 ? 100.0 * double(s.bytes_read) / double(s.record_bytes) : 100.0;
  std::snprintf(text, sizeof text, "read %.1f MB a frame, %.1f%% of the records; %llu of %llu frames by the view", per / 1e6,
                share, (unsigned long long)s.frames_by_demand, (unsigned long long)s.frames_read);
  return text;
}

}  // namespace sluice::app
