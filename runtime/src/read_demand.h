// Deciding what to read of a frame: the tiers of each cell the views need
// (demand.h's rule), under the latest demand set.
//
// Threads: set() from any thread (through DemandBox, a triple buffer whose
// writers never block the reader); everything else is the reader
// thread's. A frame's demand is applied once, when its table is parsed,
// and what it read of each cell is kept in its slot, so that a later demand
// can tell whether the frame falls short of it (a refinement read).
#pragma once

#include <cstdint>

#include "counters.h"
#include "demand_box.h"
#include "slot.h"

namespace sluice::runtime::detail {

class ReadDemand {
 public:
  ReadDemand(const ViewDemand& first, Counters& counters, uint32_t most_chunks)
      : box_(first), counters_(counters), most_chunks_(most_chunks) {}

  // Any thread.
  void set(const ViewDemand& demand) { box_.set(demand); }

  // --- the reader thread ---
  // Whether the latest demand leaves something out (frames are then read by
  // their wanted records).
  bool leaves_out() { return !box_.latest().everything(); }
  // Keeps the tiers the latest demand needs of the frame's cells and records
  // what was kept (slot.cells). No allocation after a slot's first use.
  void apply(Slot& slot) {
    const size_t before = slot.header.chunks.size();
    if (slot.cells.capacity() < most_chunks_) slot.cells.reserve(most_chunks_);  // once per slot
    apply_demand(box_.latest(), slot.header, slot.cells);
    slot.demand_applied = true;
    if (slot.header.chunks.size() != before) counters_.frames_by_demand.fetch_add(1, std::memory_order_relaxed);
  }
  // Whether the frame in `slot` lacks tiers the latest demand needs.
  bool short_of(const Slot& slot) {
    return slot.demand_applied && runtime::short_of(box_.latest(), slot.cells, slot.header.blob_voxel);
  }

 private:
  DemandBox box_;
  Counters& counters_;
  uint32_t most_chunks_;  // of any frame in the file
};

}  // namespace sluice::runtime::detail
