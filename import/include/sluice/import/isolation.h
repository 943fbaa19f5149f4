// sluice/import/isolation.h: reading frames in worker processes, so that a
// third-party reader (VTK's XML readers) crashing or hanging on a damaged
// file ends as an io::Error naming that file and frame instead of ending the
// caller's process.
//
// A worker is an executable started as `WORKER --import-worker FD SPEC =IDS
// [ATTRIBUTE...]` (posix_spawn: cheap, whatever the caller's size) whose
// main calls run_worker(). It opens the same source and serves frame
// requests over a socket pair: the request is the frame index, the answer
// the frame or its io::Error. Workers start on demand, one per concurrent
// read, and are reused; one that dies is replaced. Costs measured in
// docs/import.md (Crash isolation).
//
// Threads: a worker-backed source's read() may be called concurrently (each
// call takes its own worker). Errors: io::Error, naming the file and frame.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "sluice/import/source.h"

namespace sluice::import {

enum class Isolation : uint8_t {
  InProcess,        // every reader runs in the caller's process (fastest to start)
  WorkerProcesses,  // third-party readers run in worker processes
};

struct IsolationPolicy {
  Isolation mode = Isolation::WorkerProcesses;
  // The worker executable. Empty: $SLUICE_IMPORT_WORKER if set, else
  // sluice-import-worker as built, else as installed (libexec/sluice). An
  // executable that calls run_worker() first in its main may name itself
  // (the `sluice` command does: "/proc/self/exe").
  std::string worker;
  // A worker that takes longer for one frame is killed; the frame is bad.
  std::chrono::seconds read_limit{120};
};

// Opens `spec` as open_source() does; under WorkerProcesses a source read by
// a third-party reader (SourceInfo::third_party_reader) reads its frames in
// workers. frame_count, info and names come from this process's source.
std::unique_ptr<FrameSource> open_isolated(const std::string& spec, const SourceOptions& options,
                                           const IsolationPolicy& policy);

// The worker executable `policy.worker` resolves to (see IsolationPolicy).
// Throws io::Error when none is found.
std::string worker_executable(const IsolationPolicy& policy);

// A worker's main: true when argv asks for one (`--import-worker` first);
// it then served until its parent closed the socket, and `status` is its
// exit status. Call it before anything else in main().
bool run_worker(int argc, char** argv, int& status);

}  // namespace sluice::import
