// sluice/import/convert_mpi.h: convert() over the ranks of an MPI
// communicator, into one `.sluice` file written through MPI-IO: for
// simulation output too large for one machine's conversion
// (docs/convert_mpi.md). Built with SLUICE_MPI (target sluice::import_mpi).
//
// Collective: every rank of `comm` calls convert_mpi with the same options
// and output, from the thread that initialized MPI (MPI_THREAD_FUNNELED is
// enough: the frames' worker threads never call MPI).
//
// How: rank 0 decides what convert() decides from the first frames (header,
// spacing, LOD source, attributes, times, the provisional up axis) and
// broadcasts it. The frames are dealt in rounds: in each, every rank takes
// the next block of `jobs + 1` frames, reads and encodes them with its own
// threads (TBB), and all ranks write their records in one collective write,
// at offsets from an exclusive scan of the encoded sizes. Rank 0 gathers
// each frame's table and notes, writes the header, the index and the
// footer, and settles the up axis at the end. The file is byte for byte
// what convert() writes for the same input and options.
//
// Output: as convert(): written to `output + ".partial"`, renamed when
// complete. A rank that dies leaves the `.partial` (its frames before the
// last round are whole; `sluice recover` rebuilds the file from them) and
// never a file that looks complete.
//
// Observer: its functions run on rank 0 only (other ranks may pass none),
// in frame order. jobs: threads per rank; 0: the node's cores divided
// among the ranks on that node.
// Errors: as convert(), on every rank alike: io::Error for bad input or
// options; ConvertStopped at a bad frame (its message the serial one, with
// the rank that read the frame) once the frames before it are written, or
// when a write failed.
// Summary: complete on rank 0; other ranks count the frames, particles and
// input bytes they converted themselves.
#pragma once

#include <mpi.h>

#include "sluice/import/convert.h"

namespace sluice::import {

ConvertSummary convert_mpi(const ConvertOptions& options, const std::string& output, MPI_Comm comm,
                           const ConvertObserver& observer = {});

}  // namespace sluice::import
