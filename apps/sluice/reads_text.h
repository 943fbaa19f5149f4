// What the players say about reading by the view, for the HUD and summaries.
#pragma once

#include <string>

#include "sluice/runtime/stats.h"

namespace sluice::app {

// "read 23.8 MB a frame, 3.2% of the records; 120 of 120 frames by the view"
// (bytes read per frame read and their share of those frames' whole records).
std::string reads_text(const runtime::PipelineStats& stats);

}  // namespace sluice::app
