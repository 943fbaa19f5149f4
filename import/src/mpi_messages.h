// What the ranks of an MPI conversion tell each other (convert_mpi.cpp),
// as bytes: the plan rank 0 decides, errors, and what each frame a rank
// wrote tells rank 0 (its table for the index, its notes for the tally).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "frame_work.h"
#include "sluice/io/format.h"
#include "wire.h"

namespace sluice::import {

void put_error(WireWriter& w, const io::Error& e);
io::Error get_error(WireReader& r);

// What rank 0 decided before the frames, for the other ranks.
struct Plan {
  io::FileHeader header;  // provisional up axis
  SourceOptions source;   // ids and attributes as rank 0 opened the input
  io::Aabb shape_box;     // frames_settings' shape box
  double time_step = 0;
  uint64_t from = 0;      // the first frame that reads
  uint64_t frames = 0;    // in the input
};
void put_plan(WireWriter& w, const Plan& p);
Plan get_plan(WireReader& r);

// A frame as rank 0 needs it: the summary of a frame written for the index
// (or the error of one that was not) and what the tally is told.
struct FrameFacts {
  uint64_t frame = 0;
  std::optional<io::Error> error;
  int rank = 0;                 // that read it
  uint64_t record_bytes = 0;
  io::FrameSummary summary;  // of the record's table
  uint64_t input_bytes = 0;
  std::vector<std::string> repairs;
  std::optional<io::FrameShape> shape;
  bool time_given = false;
  io::FarReport far;
};
// `w` as written (numbered) by rank `rank`.
void put_facts(WireWriter& w, const FrameWork& work, int rank);
FrameFacts get_facts(WireReader& r);

}  // namespace sluice::import
