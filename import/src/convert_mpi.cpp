// convert_mpi(): convert() over MPI ranks, one file through MPI-IO (see
// sluice/import/convert_mpi.h), in the steps of MpiConversion::run(). Every
// collective call (mpi_collectives.h) is reached by every rank in the same
// order: errors are agreed before any rank throws.
#include "sluice/import/convert_mpi.h"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>

#include "convert_steps.h"
#include "mpi_collectives.h"
#include "mpi_messages.h"
#include "mpi_timeline.h"
#include "read_ahead.h"
#include "sluice/import/freed_memory.h"
#include "sluice/io/writer.h"

namespace sluice::import {

using namespace sluice::io;  // the container's types: frames, headers, indexes
using io::Error;  // (not sluice::Error, its base)
namespace {

Ranks ranks_of(MPI_Comm comm) {
  Ranks r{comm};
  MPI_Comm_rank(comm, &r.rank);
  MPI_Comm_size(comm, &r.size);
  return r;
}

// Threads per rank: given, or the node's cores shared among its ranks.
int threads_per_rank(const ConvertOptions& o, const Ranks& r) {
  if (o.jobs > 0) return o.jobs;
  MPI_Comm node;
  MPI_Comm_split_type(r.comm, MPI_COMM_TYPE_SHARED, r.rank, MPI_INFO_NULL, &node);
  int on_node = 1;
  MPI_Comm_size(node, &on_node);
  MPI_Comm_free(&node);
  return std::max(1, tbb::info::default_concurrency() / std::max(1, on_node));
}

// Test hook (fault injection): SLUICE_MPI_FAULT=exit:RANK ends that rank
// (std::_Exit(3), as a crash would) once its first round's records are
// written, so tests see what a rank that dies mid-conversion leaves.
void injected_fault(const Ranks& r) {
  const char* fault = std::getenv("SLUICE_MPI_FAULT");
  if (fault && std::string(fault) == "exit:" + std::to_string(r.rank)) std::_Exit(3);
}

// Rank 0's view of the conversion: what it decided, the index it builds,
// the tally that tells the observer.
struct Root {
  Prepared prepared;
  std::optional<OutputLock> lock;
  IndexBuilder index{0};
  std::optional<FrameTally> tally;
  uint64_t written_end = 0;  // the output's bytes so far, for progress
  std::vector<SkippedFrame> skipped;
  std::optional<Error> stopped;  // the bad frame the conversion stopped at
  ConvertSummary summary;
};

// Rank 0 takes one frame's facts: into the index and the tally, or the
// skipped list, or the stop.
void take_facts(Root& root, const ConvertOptions& o, FrameFacts f, int ranks) {
  if (f.error) {
    const Error& e = *f.error;
    if (o.skip_bad) {
      root.skipped.push_back({f.frame, root.prepared.in.source->frame_name(f.frame), e.what()});
      return;
    }
    root.stopped = Error(e.where(), e.message() + " (read on rank " + std::to_string(f.rank) + " of " +
                                        std::to_string(ranks) + ")");
    return;
  }
  root.index.add(f.summary, root.written_end);
  root.written_end += f.record_bytes;
  root.summary.frames++;
  root.summary.particles += f.summary.entry.count_in(LayerSet::particles());
  root.summary.input_bytes += f.input_bytes;
  (*root.tally)({f.frame, f.input_bytes, f.repairs, f.shape, f.time_given, f.far});
}

// One conversion over the ranks, step by step (run()).
class MpiConversion {
 public:
  MpiConversion(const ConvertOptions& o, const std::string& output, MPI_Comm comm, const ConvertObserver& observer)
      : o_(o), output_(output), partial_(output + ".partial"), observer_(observer), r_(ranks_of(comm)), timeline_(r_) {
    threads_ = threads_per_rank(o, r_);
    batch_ = uint64_t(threads_) + 1;
  }

  ConvertSummary run() {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads_));
    decide();
    open_input();
    start_file();
    for (uint64_t base = plan_.from; base < plan_.frames && stop_at_ == UINT64_MAX; base += batch_ * uint64_t(r_.size)) {
      convert_round(base);
    }
    finish();
    timeline_.write(r_);
    return summary();
  }

 private:
  // Rank 0 decides what convert() decides; every rank learns the plan. The
  // others read their first frames meanwhile (what rank 0 does first takes
  // seconds for large frames: read_ahead.h).
  void decide() {
    const auto span = timeline_.span("decide");
    // Rank 0 reads the rest of its first block meanwhile too (frame 0 it
    // reads to decide), or it would end the first round last.
    std::optional<ReadAhead> early;
    if (r_.root()) {
      early.emplace(o_, 1, batch_ - 1);
    } else {
      const auto reading = timeline_.span("read ahead");
      early.emplace(o_, batch_ * uint64_t(r_.rank), batch_);
      early->finish();
    }
    WireWriter plan_bytes;
    on_root(r_, [&] {
      root_.emplace();
      root_->prepared = prepare_conversion(o_, observer_);
      const Opened& in = root_->prepared.in;
      Plan plan;
      plan.header = root_->prepared.header;
      plan.source = in.options;
      plan.shape_box = root_->prepared.settings.shape_grid.box;
      plan.time_step = root_->prepared.settings.time_step;
      plan.from = in.from;
      plan.frames = in.source->frame_count();
      put_plan(plan_bytes, plan);
    });
    const std::vector<std::byte> sent = broadcast(r_, std::move(plan_bytes.bytes()));
    WireReader read(sent);
    plan_ = get_plan(read);
    header_ = plan_.header;
    settings_ = frames_settings(o_, header_, plan_.shape_box);
    settings_.time_step = plan_.time_step;
    if (early) {
      ReadAhead::Taken taken = early->take(plan_.source);
      early_frames_ = std::move(taken.frames);
      if (!r_.root()) own_source_ = std::move(taken.source);  // (rank 0 reads through the one it decided with)
    }
  }

  // Every rank but 0 opens the input as rank 0 did (unless its read-ahead did).
  void open_input() {
    const auto span = timeline_.span("open input");
    on_each(r_, [&] {
      if (r_.root()) return;
      if (!own_source_) own_source_ = open_isolated(o_.input, plan_.source, o_.isolation);
      if (own_source_->frame_count() != plan_.frames) {
        throw Error({o_.input}, "rank " + std::to_string(r_.rank) + " sees " + std::to_string(own_source_->frame_count()) +
                                    " frames, rank 0 " + std::to_string(plan_.frames) +
                                    ": the input must be the same path with the same files on every node");
      }
    });
    source_ = r_.root() ? root_->prepared.in.source.get() : own_source_.get();
  }

  // The output's lock and `.partial`, its head; rank 0's index and tally.
  void start_file() {
    const auto span = timeline_.span("start file");
    on_root(r_, [&] { root_->lock.emplace(output_); });
    file_.emplace(r_, partial_);
    const std::vector<std::byte> head = container_head(header_);
    file_end_ = head.size();
    on_root(r_, [&] {
      file_->write_at(0, head);
      root_->written_end = head.size();
      root_->index = IndexBuilder(header_.attributes.size());
      root_->tally.emplace(o_, root_->prepared.in, root_->prepared.header, root_->prepared.settings, observer_,
                           rewrite_header(), [this] { return root_->written_end; });
    });
  }

  HeaderChanged rewrite_header() {
    return [this](const FileHeader& h) { file_->write_at(0, container_head(h)); };
  }

  // One round: this rank's block encoded, every rank's records written,
  // rank 0 told what they tell.
  void convert_round(uint64_t base) {
    std::vector<FrameWork> works = encode_block(std::min(plan_.frames, base + batch_ * uint64_t(r_.rank)),
                                                std::min(plan_.frames, base + batch_ * uint64_t(r_.rank + 1)));
    // The first bad frame of the round stops the conversion after the frames before it.
    uint64_t first_bad = UINT64_MAX;
    for (const FrameWork& w : works) {
      if (w.error && !o_.skip_bad) first_bad = std::min(first_bad, w.frame);
    }
    {
      const auto span = timeline_.span("wait");
      wait_for_all(r_);
      MPI_Allreduce(&first_bad, &stop_at_, 1, MPI_UINT64_T, MPI_MIN, r_.comm);
    }
    write_block(works);
    tell_root(works);
  }

  // Frames [begin, end), read (or taken as read) and encoded on this rank's threads.
  std::vector<FrameWork> encode_block(uint64_t begin, uint64_t end) {
    std::vector<FrameWork> works(end - begin);
    tbb::parallel_for(begin, end, [&](uint64_t f) {
      std::optional<ParticleFrame> read;
      if (r_.root() && f == plan_.from) {
        read = std::move(root_->prepared.in.first);
      } else if (const auto it = early_frames_.find(f); it != early_frames_.end()) {
        read = std::move(it->second);
      }
      const auto span = timeline_.span(read ? "encode" : "read and encode", int64_t(f));
      works[f - begin] = convert_frame(*source_, std::move(read), f, header_, settings_);
    });
    early_frames_.clear();
    return works;
  }

  bool written(const FrameWork& w) const { return w.frame < stop_at_ && !w.error; }

  // This rank's records after every earlier rank's of the round (an
  // exclusive scan of the sizes), numbered, in one collective write.
  void write_block(std::vector<FrameWork>& works) {
    uint64_t local[2] = {0, 0}, before[2] = {0, 0}, total[2] = {0, 0};  // bytes, frames
    for (const FrameWork& w : works) {
      if (!written(w)) continue;
      local[0] += w.encoded.record.size();
      local[1] += 1;
    }
    MPI_Exscan(local, before, 2, MPI_UINT64_T, MPI_SUM, r_.comm);
    if (r_.root()) before[0] = before[1] = 0;  // (MPI_Exscan leaves rank 0's undefined)
    MPI_Allreduce(local, total, 2, MPI_UINT64_T, MPI_SUM, r_.comm);
    std::vector<const std::vector<std::byte>*> records;
    uint64_t number = frames_written_ + before[1];
    for (FrameWork& w : works) {
      if (!written(w)) continue;
      set_frame_number(w.encoded, uint32_t(number++), header_.attributes.size());
      records.push_back(&w.encoded.record);
      mine_.frames++;
      mine_.particles += count_in(w.encoded.header, LayerSet::particles());
      mine_.input_bytes += w.input_bytes;
    }
    const auto span = timeline_.span("write");
    const int code = file_->write_records_at_all(file_end_ + before[0], records);
    try {
      std::optional<Error> failed;
      if (code != MPI_SUCCESS) {
        failed = Error({partial_}, "rank " + std::to_string(r_.rank) + " could not write its frames: " + mpi_error_text(code));
      }
      agree(r_, failed);
    } catch (const Error& e) {
      throw ConvertStopped(e, partial_, frames_written_, false);
    }
    file_end_ += total[0];
    frames_written_ += total[1];
  }

  // Rank 0 indexes the round's frames and tells what they tell, in order.
  void tell_root(const std::vector<FrameWork>& works) {
    const auto span = timeline_.span("tell rank 0");
    WireWriter facts;
    for (const FrameWork& w : works) {
      if (w.frame <= stop_at_) put_facts(facts, w, r_.rank);
    }
    const std::vector<std::byte> all = gather(r_, facts.bytes());
    injected_fault(r_);  // (after the gather: every rank's write of the round has returned)
    on_root(r_, [&] {
      WireReader read(all);
      while (!read.done()) take_facts(*root_, o_, get_facts(read), r_.size);
    });
  }

  // The stop, if any, on every rank; then rank 0 ends the file as convert()
  // does: totals, the up axis, the index; closed, renamed.
  void finish() {
    const auto span = timeline_.span("finish");
    std::optional<Error> stopped;
    if (stop_at_ != UINT64_MAX) {
      WireWriter w;
      if (r_.root()) put_error(w, *root_->stopped);
      const std::vector<std::byte> bytes = broadcast(r_, std::move(w.bytes()));
      WireReader read(bytes);
      stopped = get_error(read);
    }
    on_root(r_, [&] {
      Opened& in = root_->prepared.in;
      in.skipped.insert(in.skipped.end(), root_->skipped.begin(), root_->skipped.end());
      tell_totals(o_, *root_->tally, in.skipped, observer_);
      if (!stopped) settle_up(o_, in, *root_->tally, root_->prepared.first_shape, root_->prepared.header, rewrite_header(), observer_);
      file_->write_at(file_end_, container_tail(root_->index.index(), header_.attributes.size(), file_end_));
    });
    const int closed = file_->sync_and_close();
    try {
      std::optional<Error> failed;
      if (closed != MPI_SUCCESS) failed = Error({partial_}, "could not flush the file to disk: " + mpi_error_text(closed));
      agree(r_, failed);
    } catch (const Error& e) {
      throw ConvertStopped(e, partial_, frames_written_, false);
    }
    on_root(r_, [&] { std::filesystem::rename(partial_, output_); });
    if (stopped) throw ConvertStopped(*stopped, output_, frames_written_, true);
  }

  ConvertSummary summary() {
    ConvertSummary s = r_.root() ? std::move(root_->summary) : mine_;
    if (r_.root()) {
      s.skipped = std::move(root_->prepared.in.skipped);
      s.far_particles = root_->tally->far_particles;
      s.far_frames = root_->tally->far_frames;
      s.header = root_->prepared.header;
    } else {
      s.header = header_;
    }
    s.elapsed = std::chrono::steady_clock::now() - start_;
    return s;
  }

  const ConvertOptions& o_;
  const std::string output_, partial_;
  const ConvertObserver& observer_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  Ranks r_;
  Timeline timeline_;  // SLUICE_MPI_TIMELINE (mpi_timeline.h)
  int threads_ = 1;
  uint64_t batch_ = 2;  // frames a rank takes a round

  Plan plan_;
  FileHeader header_;
  FramesSettings settings_;
  std::optional<Root> root_;                       // rank 0's side
  std::unique_ptr<FrameSource> own_source_;        // every other rank's
  const FrameSource* source_ = nullptr;
  std::map<uint64_t, ParticleFrame> early_frames_;  // read while rank 0 decided
  std::optional<SharedFile> file_;
  uint64_t file_end_ = 0, frames_written_ = 0;
  uint64_t stop_at_ = UINT64_MAX;  // the first bad frame
  ConvertSummary mine_;            // what this rank converted
};

}  // namespace

ConvertSummary convert_mpi(const ConvertOptions& o, const std::string& output, MPI_Comm comm,
                           const ConvertObserver& observer) {
  const KeepFreedMemory keep;  // VTK and the importer allocate per frame (freed_memory.h)
  return MpiConversion(o, output, comm, observer).run();
}

}  // namespace sluice::import
