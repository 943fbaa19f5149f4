// Frames read in worker processes, so that a third-party reader crashing or
// hanging on a damaged file ends as an io::Error naming that file and frame
// instead of ending sluice (and the conversion with it).
//
// A worker is this executable started as `sluice --import-worker ...`
// (posix_spawn of /proc/self/exe: cheap, whatever this process's size). It
// opens the same source and serves frame requests over a socket pair: the
// request is the frame index, the answer the frame or its io::Error. Workers
// start on demand, one per concurrent read, and are reused; one that dies is
// replaced. Costs measured in docs/import.md (Crash isolation).
//
// Threads: read() may be called concurrently (each call takes its own
// worker).
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "sluice/io/import.h"

namespace sluice::app {

// Wraps `source` (opened from `spec` with `options`): frame_count, info and
// names come from it; read() runs in a worker, which must answer within
// `limit` per frame.
std::unique_ptr<io::FrameSource> isolate(std::unique_ptr<io::FrameSource> source, const std::string& spec,
                                         const io::ImportOptions& options, std::chrono::seconds limit);

// The worker's main: true when argv asks for one (it then ran and `status`
// is its exit status).
bool run_import_worker(int argc, char** argv, int& status);

}  // namespace sluice::app
