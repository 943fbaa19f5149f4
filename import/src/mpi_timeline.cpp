#include "mpi_timeline.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "wire.h"

namespace sluice::import {

Timeline::Timeline(const Ranks& r) {
  int on = 0;
  if (r.root()) {
    const char* path = std::getenv("SLUICE_MPI_TIMELINE");
    if (path && *path) {
      path_ = path;
      on = 1;
    }
  }
  MPI_Bcast(&on, 1, MPI_INT, 0, r.comm);
  on_ = on != 0;
  if (on_) MPI_Barrier(r.comm);  // (a common origin for every rank's clock)
  origin_ = std::chrono::steady_clock::now();
}

double Timeline::now() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - origin_).count(); }

Timeline::Span::Span(Timeline* t, const char* step, int64_t frame)
    : timeline_(t), step_(step), frame_(frame), start_(t ? t->now() : 0.0) {}

Timeline::Span::~Span() {
  if (!timeline_) return;
  const double end = timeline_->now();
  const std::lock_guard lock(timeline_->mutex_);
  timeline_->noted_.push_back({step_, frame_, start_, end});
}

void Timeline::write(const Ranks& r) {
  if (!on_) return;
  WireWriter mine;
  mine.bytes().reserve(16 + noted_.size() * 64);
  mine.put<int>(r.rank);
  mine.put<uint64_t>(noted_.size());
  for (const Noted& n : noted_) {
    mine.put_string(n.step);
    mine.put(n.frame);
    mine.put(n.start);
    mine.put(n.end);
  }
  const std::vector<std::byte> all = gather(r, mine.bytes());
  if (!r.root()) return;
  std::ofstream out(path_);
  out << "rank,step,frame,start_s,end_s\n" << std::fixed;
  out.precision(6);
  WireReader read(all);
  while (!read.done()) {
    const int rank = read.get<int>();
    const uint64_t count = read.get<uint64_t>();
    for (uint64_t i = 0; i < count; ++i) {
      const std::string step = read.get_string();
      const int64_t frame = read.get<int64_t>();
      const double start = read.get<double>(), end = read.get<double>();
      out << rank << ',' << step << ',' << frame << ',' << start << ',' << end << '\n';
    }
  }
  out.flush();
  if (!out) std::fprintf(stderr, "sluice: could not write the timeline %s\n", path_.c_str());
}

}  // namespace sluice::import
