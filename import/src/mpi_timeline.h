// Where an MPI conversion's time goes, rank by rank: with
// SLUICE_MPI_TIMELINE=FILE in rank 0's environment, each rank notes the
// spans of its steps (deciding, reading ahead, each frame's read and
// encoding, waiting for the others, the collective write, ...), and at the
// end rank 0 writes every rank's spans to FILE as CSV:
//   rank,step,frame,start_s,end_s
// in seconds from a barrier every rank passed when the conversion began
// (clocks of one node agree; across nodes they are each node's own).
// Off (the default), nothing is noted and nothing is exchanged.
// Threads: span() may be called from any of a rank's threads.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "mpi_collectives.h"

namespace sluice::import {

class Timeline {
 public:
  // Collective: rank 0 decides whether it is on and tells the others.
  explicit Timeline(const Ranks& r);

  // A step's span, noted when the object dies. `frame`: -1 for none.
  class Span {
   public:
    Span(Timeline* t, const char* step, int64_t frame);
    ~Span();
    Span(const Span&) = delete;
    Span& operator=(const Span&) = delete;

   private:
    Timeline* timeline_;
    const char* step_;
    int64_t frame_;
    double start_;
  };
  Span span(const char* step, int64_t frame = -1) { return Span(on_ ? this : nullptr, step, frame); }

  // Collective: every rank's spans to rank 0, which writes the file (a file
  // it cannot write is said on stderr, and the conversion is not failed).
  void write(const Ranks& r);

 private:
  struct Noted {
    const char* step;
    int64_t frame;
    double start, end;
  };
  double now() const;

  bool on_ = false;
  std::string path_;  // rank 0's
  std::chrono::steady_clock::time_point origin_;
  std::mutex mutex_;
  std::vector<Noted> noted_;
};

}  // namespace sluice::import
