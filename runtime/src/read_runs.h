// The byte runs a frame's wanted records are read in (format 2.0 makes a
// view's demand a few of them: docs/runtime.md, "Reads in runs").
//
// A pure function of the wanted records' offsets: records closer than
// `gap` are joined with the bytes between them (one large read is cheaper
// for a disk than two with a small gap), and every run is widened to
// `align` (O_DIRECT). Used by the reader thread (read_target.cpp) and by
// tests; allocates nothing once `out` has room.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "sluice/io/format.h"

namespace sluice::runtime::detail {

// A range of the read target's buffer, dst[at, at + length), read from the
// file at the buffer's offset + at; only its first `required` bytes need
// exist in the file (the rest is alignment padding past its end).
struct ByteRun {
  uint64_t at = 0, length = 0, required = 0;
};

// Records at most this far apart are read as one run: 64 KiB reads from 8
// threads reach 88% of the GPU box's sequential rate (docs/runtime.md),
// while reading 64 KiB through costs at most a 64 KiB read.
inline constexpr uint64_t kRunGap = 64 << 10;

// Whether a record starting at `begin` is read with the open run [from, to):
// it lies after the run's start and at most `gap` past its end. The one
// rule of plan_runs() and of the relay's reads (record_read.cpp).
inline bool joins_run(uint64_t from, uint64_t to, uint64_t begin, uint64_t gap) {
  return begin >= from && begin <= to + gap;
}

struct RunLimits {
  uint64_t align = 1;          // offsets and lengths of reads are multiples of it (1: none)
  uint64_t gap = kRunGap;      // records at most this far apart share a run
  uint64_t piece = 8 << 20;    // a run longer than this is read in pieces of about equal length
};

// Runs covering `records` (in file order, payload offsets from the start
// of the frame record, which lies at `record_at` in a buffer of `size`
// bytes whose first `need` come from the file). Returns the number of
// runs before splitting into pieces; `out` gets the pieces, in order.
// Bytes below `skip` (already read: the table; a multiple of `align`) are
// left out.
size_t plan_runs(std::span<const io::RecordPart> records, uint64_t record_at, uint64_t size, uint64_t need,
                 uint64_t skip, const RunLimits& limits, std::vector<ByteRun>& out);

}  // namespace sluice::runtime::detail
