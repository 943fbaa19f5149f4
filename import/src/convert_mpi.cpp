// convert_mpi(): convert() over MPI ranks, one file through MPI-IO (see
// sluice/import/convert_mpi.h). Every collective call below is reached by
// every rank in the same order: errors are agreed (broadcast or reduced)
// before any rank throws, so no rank is left waiting in a collective.
#include "sluice/import/convert_mpi.h"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <thread>

#include "convert_steps.h"
#include "mpi_messages.h"
#include "read_ahead.h"
#include "sluice/import/freed_memory.h"
#include "sluice/io/assembly.h"
#include "sluice/io/output_lock.h"

namespace sluice::import {

using namespace sluice::io;  // the container's types: frames, headers, indexes
using io::Error;  // (not sluice::Error, its base)
namespace {

struct Ranks {
  MPI_Comm comm;
  int rank = 0, size = 1;
  bool root() const { return rank == 0; }
};

int checked_int(uint64_t n, const char* what) {
  if (n > uint64_t(INT_MAX)) throw Error({}, std::string(what) + " is over 2 GiB: too large for one MPI message");
  return int(n);
}

// `bytes` of rank `from` on every rank.
std::vector<std::byte> broadcast(const Ranks& r, std::vector<std::byte> bytes, int from = 0) {
  uint64_t n = bytes.size();
  MPI_Bcast(&n, 1, MPI_UINT64_T, from, r.comm);
  bytes.resize(n);
  MPI_Bcast(bytes.data(), checked_int(n, "a broadcast"), MPI_BYTE, from, r.comm);
  return bytes;
}

// Returns once every rank has called it, sleeping meanwhile. MPI's own
// waits spin on a core, which a rank's reader processes (isolation.h) and
// the ranks still encoding need: a rank that finished its frames early
// would slow those that did not.
void wait_for_all(const Ranks& r) {
  MPI_Request arrived;
  MPI_Ibarrier(r.comm, &arrived);
  for (int done = 0;;) {
    MPI_Test(&arrived, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

// Throws on every rank the error of the lowest rank that has one (none: returns).
void agree(const Ranks& r, const std::optional<Error>& mine) {
  wait_for_all(r);  // (rank 0 may have worked long: reading the first frames)
  const int have = mine ? r.rank : INT_MAX;
  int lowest = INT_MAX;
  MPI_Allreduce(&have, &lowest, 1, MPI_INT, MPI_MIN, r.comm);
  if (lowest == INT_MAX) return;
  WireWriter w;
  if (r.rank == lowest) put_error(w, *mine);
  const std::vector<std::byte> bytes = broadcast(r, std::move(w.bytes()), lowest);
  WireReader read(bytes);
  throw get_error(read);
}

// Runs `step` on this rank; what it throws is thrown on every rank alike.
void on_each(const Ranks& r, const std::function<void()>& step) {
  std::optional<Error> failed;
  try {
    step();
  } catch (const Error& e) {
    failed = e;
  } catch (const std::exception& e) {
    failed = Error({}, e.what());
  }
  agree(r, failed);
}

// Runs `step` on rank 0; what it throws is thrown on every rank alike.
void on_root(const Ranks& r, const std::function<void()>& step) {
  on_each(r, [&] {
    if (r.root()) step();
  });
}

// Every rank's bytes, concatenated in rank order, on rank 0.
std::vector<std::byte> gather(const Ranks& r, const std::vector<std::byte>& mine) {
  const int n = checked_int(mine.size(), "a rank's frame tables");
  std::vector<int> counts(size_t(r.root() ? r.size : 0)), at(counts.size());
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, r.comm);
  std::vector<std::byte> all;
  if (r.root()) {
    uint64_t total = 0;
    for (size_t i = 0; i < counts.size(); ++i) {
      at[i] = checked_int(total, "a round's frame tables");
      total += uint64_t(counts[i]);
    }
    all.resize(total);
  }
  MPI_Gatherv(mine.data(), n, MPI_BYTE, all.data(), counts.data(), at.data(), MPI_BYTE, 0, r.comm);
  return all;
}

std::string mpi_error_text(int code) {
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  return std::string(text, size_t(length));
}

// The output file, opened by every rank, closed collectively.
class SharedFile {
 public:
  SharedFile(const Ranks& r, const std::string& path) : path_(path) {
    const int opened = MPI_File_open(r.comm, path.c_str(), MPI_MODE_CREATE | MPI_MODE_WRONLY, MPI_INFO_NULL, &file_);
    std::optional<Error> failed;
    if (opened != MPI_SUCCESS) failed = Error({path}, "rank " + std::to_string(r.rank) + " could not create it: " + mpi_error_text(opened));
    try {
      agree(r, failed);
    } catch (...) {
      if (opened == MPI_SUCCESS) MPI_File_close(&file_);
      throw;
    }
    MPI_File_set_size(file_, 0);  // as O_TRUNC: a longer file of an earlier run is cut
  }
  ~SharedFile() {
    if (file_ != MPI_FILE_NULL) MPI_File_close(&file_);
  }
  SharedFile(const SharedFile&) = delete;
  SharedFile& operator=(const SharedFile&) = delete;

  // Rank 0's own writes (header, index). Throws io::Error.
  void write_at(uint64_t at, std::span<const std::byte> bytes) {
    for (uint64_t done = 0; done < bytes.size();) {
      const int n = int(std::min<uint64_t>(bytes.size() - done, 1u << 30));
      MPI_Status status;
      const int code = MPI_File_write_at(file_, MPI_Offset(at + done), bytes.data() + done, n, MPI_BYTE, &status);
      if (code != MPI_SUCCESS) throw Error({path_}, "could not write: " + mpi_error_text(code));
      done += uint64_t(n);
    }
  }

  // Every rank's records, contiguous from `at`, in one collective write
  // (no copy: the records are described where they lie). Returns the MPI
  // error code.
  int write_records_at_all(uint64_t at, const std::vector<const std::vector<std::byte>*>& records) {
    std::vector<int> lengths;
    std::vector<MPI_Aint> places;
    for (const std::vector<std::byte>* record : records) {
      for (uint64_t done = 0; done < record->size();) {
        const int n = int(std::min<uint64_t>(record->size() - done, 1u << 30));
        MPI_Aint place;
        MPI_Get_address(record->data() + done, &place);
        lengths.push_back(n);
        places.push_back(place);
        done += uint64_t(n);
      }
    }
    MPI_Datatype layout;
    MPI_Type_create_hindexed(int(lengths.size()), lengths.data(), places.data(), MPI_BYTE, &layout);
    MPI_Type_commit(&layout);
    MPI_Status status;
    const int code = MPI_File_write_at_all(file_, MPI_Offset(at), MPI_BOTTOM, lengths.empty() ? 0 : 1, layout, &status);
    MPI_Type_free(&layout);
    return code;
  }

  int sync_and_close() {
    int code = MPI_File_sync(file_);
    const int closed = MPI_File_close(&file_);
    return code != MPI_SUCCESS ? code : closed;
  }

 private:
  std::string path_;
  MPI_File file_ = MPI_FILE_NULL;
};

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

// The frames one rank handles in one round.
struct Round {
  uint64_t begin = 0, end = 0;
};

// Rank 0 takes one frame's facts: into the index and the tally, or the
// skipped list, or the stop.
void take_facts(Root& root, const ConvertOptions& o, const FileHeader& header, FrameFacts f, int ranks) {
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
  const FrameHeader table = parse_frame_table_bytes(f.table, header.attributes.size(), {"the frame table of rank " + std::to_string(f.rank)});
  root.index.add(table, root.written_end);
  root.written_end += f.record_bytes;
  root.summary.frames++;
  root.summary.particles += count_in(table, LayerSet::particles());
  root.summary.input_bytes += f.input_bytes;
  (*root.tally)({f.frame, f.input_bytes, f.repairs, f.shape, f.time_given, f.far});
}


}  // namespace

ConvertSummary convert_mpi(const ConvertOptions& o, const std::string& output, MPI_Comm comm,
                           const ConvertObserver& observer) {
  const auto start = std::chrono::steady_clock::now();
  Ranks r{comm};
  MPI_Comm_rank(comm, &r.rank);
  MPI_Comm_size(comm, &r.size);
  const KeepFreedMemory keep;  // VTK and the importer allocate per frame (freed_memory.h)
  const int threads = threads_per_rank(o, r);
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));

  // Rank 0 decides; every rank learns the plan (the others read meanwhile).
  const uint64_t batch = uint64_t(threads) + 1;
  // (what rank 0 does first takes seconds for large frames: read_ahead.h)
  std::optional<ReadAhead> early;
  if (!r.root()) {
    early.emplace(o, batch * uint64_t(r.rank), batch);
    early->finish();
  }
  std::optional<Root> root;
  WireWriter plan_bytes;
  on_root(r, [&] {
    root.emplace();
    root->prepared = prepare_conversion(o, observer);
    const Opened& in = root->prepared.in;
    Plan plan;
    plan.header = root->prepared.header;
    plan.source = in.options;
    plan.shape_box = root->prepared.settings.shape_grid.box;
    plan.time_step = root->prepared.settings.time_step;
    plan.from = in.from;
    plan.frames = in.source->frame_count();
    put_plan(plan_bytes, plan);
  });
  const std::vector<std::byte> sent = broadcast(r, std::move(plan_bytes.bytes()));
  WireReader read_plan(sent);
  const Plan plan = get_plan(read_plan);
  FileHeader header = plan.header;
  FramesSettings settings = frames_settings(o, header, plan.shape_box);
  settings.time_step = plan.time_step;
  const size_t attributes = header.attributes.size();
  std::unique_ptr<FrameSource> own_source;  // every rank but 0 opens the input as rank 0 did
  std::map<uint64_t, ParticleFrame> early_frames;
  on_each(r, [&] {
    if (r.root()) return;
    ReadAhead::Taken taken = early->take(plan.source);
    early_frames = std::move(taken.frames);
    own_source = std::move(taken.source);
    if (!own_source) own_source = open_isolated(o.input, plan.source, o.isolation);
    if (own_source->frame_count() != plan.frames) {
      throw Error({o.input}, "rank " + std::to_string(r.rank) + " sees " + std::to_string(own_source->frame_count()) +
                                 " frames, rank 0 " + std::to_string(plan.frames) +
                                 ": the input must be the same path with the same files on every node");
    }
  });
  const FrameSource* source = r.root() ? root->prepared.in.source.get() : own_source.get();

  const std::string partial = output + ".partial";
  on_root(r, [&] { root->lock.emplace(output); });
  SharedFile file(r, partial);
  const std::vector<std::byte> head = container_head(header);
  on_root(r, [&] {
    file.write_at(0, head);
    root->written_end = head.size();
    root->index = IndexBuilder(attributes);
    const HeaderChanged rewrite = [&file](const FileHeader& h) { file.write_at(0, container_head(h)); };
    root->tally.emplace(o, root->prepared.in, root->prepared.header, root->prepared.settings, observer, rewrite,
                        [&root] { return root->written_end; });
  });

  ConvertSummary mine;  // what this rank converted
  uint64_t file_end = head.size(), frames_written = 0;
  uint64_t stop_at = UINT64_MAX;
  for (uint64_t base = plan.from; base < plan.frames && stop_at == UINT64_MAX; base += batch * uint64_t(r.size)) {
    const Round round{std::min(plan.frames, base + batch * uint64_t(r.rank)),
                      std::min(plan.frames, base + batch * uint64_t(r.rank + 1))};
    std::vector<FrameWork> works(round.end - round.begin);
    tbb::parallel_for(round.begin, round.end, [&](uint64_t f) {
      std::optional<ParticleFrame> read;
      if (r.root() && f == plan.from) {
        read = std::move(root->prepared.in.first);
      } else if (const auto it = early_frames.find(f); it != early_frames.end()) {
        read = std::move(it->second);
      }
      works[f - round.begin] = convert_frame(*source, std::move(read), f, header, settings);
    });

    early_frames.clear();
    // The first bad frame of the round stops the conversion after the frames before it.
    uint64_t first_bad = UINT64_MAX;
    for (const FrameWork& w : works) {
      if (w.error && !o.skip_bad) first_bad = std::min(first_bad, w.frame);
    }
    wait_for_all(r);
    MPI_Allreduce(&first_bad, &stop_at, 1, MPI_UINT64_T, MPI_MIN, comm);

    // Where this rank's records go: after every earlier rank's of the round.
    std::vector<const std::vector<std::byte>*> records;
    uint64_t local[2] = {0, 0}, before[2] = {0, 0}, total[2] = {0, 0};  // bytes, frames
    for (const FrameWork& w : works) {
      if (w.frame >= stop_at || w.error) continue;
      local[0] += w.encoded.record.size();
      local[1] += 1;
    }
    MPI_Exscan(local, before, 2, MPI_UINT64_T, MPI_SUM, comm);
    if (r.root()) before[0] = before[1] = 0;  // (MPI_Exscan leaves rank 0's undefined)
    MPI_Allreduce(local, total, 2, MPI_UINT64_T, MPI_SUM, comm);
    uint64_t number = frames_written + before[1];
    for (FrameWork& w : works) {
      if (w.frame >= stop_at || w.error) continue;
      set_frame_number(w.encoded, uint32_t(number++), attributes);
      records.push_back(&w.encoded.record);
      mine.frames++;
      mine.particles += count_in(w.encoded.header, LayerSet::particles());
      mine.input_bytes += w.input_bytes;
    }
    const int code = file.write_records_at_all(file_end + before[0], records);
    try {
      std::optional<Error> failed;
      if (code != MPI_SUCCESS) failed = Error({partial}, "rank " + std::to_string(r.rank) + " could not write its frames: " + mpi_error_text(code));
      agree(r, failed);
    } catch (const Error& e) {
      throw ConvertStopped(e, partial, frames_written, false);
    }

    // Rank 0 indexes and tells what the frames of the round tell, in order.
    WireWriter facts;
    for (const FrameWork& w : works) {
      if (w.frame <= stop_at) put_facts(facts, w, r.rank, attributes);
    }
    const std::vector<std::byte> all = gather(r, facts.bytes());
    injected_fault(r);  // (after the gather: every rank's write of the round has returned)
    on_root(r, [&] {
      WireReader read(all);
      while (!read.done()) take_facts(*root, o, header, get_facts(read), r.size);
    });
    file_end += total[0];
    frames_written += total[1];
  }

  // The stop, if any, on every rank; then rank 0 closes the file as convert() does.
  std::optional<Error> stopped;
  if (stop_at != UINT64_MAX) {
    WireWriter w;
    if (r.root()) put_error(w, *root->stopped);
    const std::vector<std::byte> bytes = broadcast(r, std::move(w.bytes()));
    WireReader read(bytes);
    stopped = get_error(read);
  }
  on_root(r, [&] {
    Opened& in = root->prepared.in;
    in.skipped.insert(in.skipped.end(), root->skipped.begin(), root->skipped.end());
    tell_totals(o, *root->tally, in.skipped, observer);
    if (!stopped) {
      const HeaderChanged rewrite = [&file](const FileHeader& h) { file.write_at(0, container_head(h)); };
      settle_up(o, in, *root->tally, root->prepared.first_shape, root->prepared.header, rewrite, observer);
    }
    file.write_at(file_end, container_tail(root->index.index(), attributes, file_end));
  });
  const int closed = file.sync_and_close();
  try {
    std::optional<Error> failed;
    if (closed != MPI_SUCCESS) failed = Error({partial}, "could not flush the file to disk: " + mpi_error_text(closed));
    agree(r, failed);
  } catch (const Error& e) {
    throw ConvertStopped(e, partial, frames_written, false);
  }
  on_root(r, [&] { std::filesystem::rename(partial, output); });
  if (stopped) throw ConvertStopped(*stopped, output, frames_written, true);

  ConvertSummary s = r.root() ? std::move(root->summary) : mine;
  if (r.root()) {
    s.skipped = std::move(root->prepared.in.skipped);
    s.far_particles = root->tally->far_particles;
    s.far_frames = root->tally->far_frames;
    s.header = root->prepared.header;
  } else {
    s.header = header;
  }
  s.elapsed = std::chrono::steady_clock::now() - start;
  return s;
}

}  // namespace sluice::import
