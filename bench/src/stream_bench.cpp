// `sluice bench stream`: the pipeline (reader thread, decode workers, a null
// consumer taking frames as fast as it can) against the machine's bounds,
// measured in the same run, from storage and from the page cache.
#include "sluice/bench/stream_bench.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>

#include "bounds.h"
#include "stream_slice.h"
#include "machine.h"
#include "sluice/io/codec.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/pipeline.h"
#include "sluice/bench/table.h"

namespace sluice::bench {

Slice slice_of(const io::ContainerReader& reader, uint64_t wanted, uint64_t page_cache_room, io::LayerSet layers) {
  const auto& index = reader.index().frames;
  const uint64_t per_particle =
      io::decoded_particle_bytes(reader.header().position_coding) + 2 * reader.header().attributes.size();
  Slice s;
  s.layers = layers;
  s.offset = index.empty() ? 0 : index.front().offset;
  for (const io::FrameIndexEntry& e : index) {
    if (wanted ? s.frames == wanted : (s.frames > 0 && s.bytes + e.bytes > page_cache_room)) break;
    ++s.frames;
    s.bytes += e.bytes;
    s.particles += e.count_in(layers);
    s.decoded += e.count_in(layers) * per_particle;
    s.read += e.layered() ? io::layers_end(reader.read_table(s.frames - 1), layers, reader.header().attributes.size()) : e.bytes;
  }
  return s;
}

namespace {

using Clock = std::chrono::steady_clock;
using runtime::EndMode;
using runtime::PipelineStats;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }


struct Pass {
  double seconds = 0;
  uint64_t frames = 0;
  runtime::PipelineRates rates;
  std::string window;  // in use / planned
  std::string io_mode;
  uint64_t cache_hits = 0;  // frames served from memory during the timing (should be 0)
  uint64_t bytes_read = 0;    // what the pipeline asked of the file during the timing
  uint64_t device_bytes = 0;  // what storage delivered meanwhile (process_read_bytes: readahead included)
};

struct PassSetup {
  int decode_threads = 1;
  int read_threads = 1;
  uint64_t memory = 0;
};

// Streams the slice through a pipeline into a null consumer. Looping passes
// run for `min_seconds` after one window of warm-up; others run once.
Pass stream(const io::ContainerReader& reader, const Slice& slice, const PassSetup& setup, bool direct, bool loop,
            double min_seconds, io::LayerSet layers) {
  runtime::HostFrameAllocator allocator;
  runtime::PipelineOptions o;
  o.decode.threads = setup.decode_threads;
  o.read.threads = setup.read_threads;
  o.read.direct_io = direct;
  o.window.budget.memory_cap = setup.memory;
  o.layers = layers;
  // A loop round a slice that fits in the window would be served from the
  // frames kept decoded; at half the slice every frame comes through again.
  if (loop) o.window.budget.max_frames = static_cast<uint32_t>(std::max<uint64_t>(2, slice.frames / 2));
  runtime::Pipeline pipeline(reader, allocator, o);
  // frame_count = the slice: a loop goes round the prefix only.
  pipeline.restart({slice.frames, 0, 1, 1, loop ? EndMode::Loop : EndMode::Stop});
  auto consume = [&](uint64_t most, double seconds) {
    const auto start = Clock::now();
    uint64_t n = 0;
    for (; n < most && (seconds <= 0 || seconds_since(start) < seconds); ++n) {
      if (pipeline.wait_next().end) break;
      const runtime::FrameHandle h = pipeline.take();
      if (h.failed()) throw io::Error(h.error()->where, h.error()->message);
    }
    return n;
  };
  if (loop) consume(pipeline.window(), 0);
  const PipelineStats before = pipeline.stats();
  const uint64_t device_before = process_read_bytes();
  const auto start = Clock::now();
  Pass p;
  p.frames = consume(loop ? std::numeric_limits<uint64_t>::max() : slice.frames, loop ? min_seconds : 0);
  p.seconds = seconds_since(start);
  p.device_bytes = process_read_bytes() - device_before;
  const PipelineStats after = pipeline.stats();
  p.bytes_read = after.bytes_read - before.bytes_read;
  p.rates = runtime::rates_between(before, after);
  p.window = std::to_string(after.active_frames) + "/" + std::to_string(after.window_frames);
  p.io_mode = after.io_mode;
  p.cache_hits = after.cache_hits - before.cache_hits;
  return p;
}

// Decode alone, records already in memory, into full-frame buffers: what the
// workers could do if reading cost nothing.
double decode_only_fps(const io::ContainerReader& reader, const Slice& slice, int threads, double min_seconds) {
  const uint64_t frames = std::min<uint64_t>(slice.frames, 8);
  std::vector<std::vector<std::byte>> records;
  std::vector<io::FrameHeader> headers;
  std::vector<std::vector<std::byte>> outputs;
  std::vector<std::pair<uint64_t, size_t>> chunks;  // (frame, chunk)
  std::vector<std::vector<uint64_t>> first;
  const size_t stride = io::decoded_particle_bytes(reader.header().position_coding);
  for (uint64_t f = 0; f < frames; ++f) {
    records.push_back(reader.read_record(f));
    headers.push_back(reader.parse_record(f, records.back()));
    io::keep_layers(headers.back(), slice.layers);
    outputs.emplace_back(headers.back().particle_count * stride);
    first.emplace_back();
    uint64_t at = 0;
    for (size_t c = 0; c < headers.back().chunks.size(); ++c) {
      chunks.emplace_back(f, c);
      first.back().push_back(at);
      at += headers.back().chunks[c].particle_count;
    }
  }
  tbb::task_arena arena(threads);
  const auto start = Clock::now();
  uint64_t passes = 0;
  do {
    arena.execute([&] {
      tbb::parallel_for(size_t(0), chunks.size(), [&](size_t i) {
        thread_local io::DecodeScratch scratch;
        const auto [f, c] = chunks[i];
        const io::ChunkDesc& chunk = headers[f].chunks[c];
        const std::span<std::byte> out = std::span(outputs[f]).subspan(first[f][c] * stride, chunk.particle_count * stride);
        io::decode_chunk(records[f], chunk, reader.header(), {out, {}}, scratch, reader.location(f, c));
      });
    });
    ++passes;
  } while (seconds_since(start) < min_seconds);
  return double(frames * passes) / seconds_since(start);
}

// Read and decode with no pipeline in between: every worker preads its own
// chunk from the page cache into a buffer of its own (which stays in its
// cache) and decodes it from there. What the cores could deliver if reading
// and decoding were one task per chunk; the pipeline copies whole records
// first, which costs memory traffic (a copy, then a second read).
double chunk_read_decode_fps(const io::ContainerReader& reader, const Slice& slice, int threads, double min_seconds) {
  const uint64_t cycle = std::min<uint64_t>(slice.frames, 16);  // frames gone round (all in the page cache)
  std::vector<io::FrameHeader> headers;
  std::vector<std::vector<uint64_t>> firsts;  // first particle of each chunk
  for (uint64_t f = 0; f < cycle; ++f) {
    headers.push_back(reader.parse_record(f, reader.read_record(f)));
    io::keep_layers(headers.back(), slice.layers);
    firsts.emplace_back(headers.back().chunks.size());
    for (size_t c = 1; c < headers.back().chunks.size(); ++c) {
      firsts.back()[c] = firsts.back()[c - 1] + headers.back().chunks[c - 1].particle_count;
    }
  }
  const size_t stride = io::decoded_particle_bytes(reader.header().position_coding);
  uint64_t most = 0;
  for (const auto& h : headers) most = std::max(most, h.particle_count);
  std::vector<std::vector<std::byte>> outputs(4, std::vector<std::byte>(most * stride, std::byte{1}));
  tbb::task_arena arena(threads);
  const auto start = Clock::now();
  uint64_t frames = 0;
  do {
    const uint64_t f = frames % cycle;
    const io::FrameHeader& h = headers[f];
    const std::vector<uint64_t>& first = firsts[f];
    std::vector<std::byte>& out = outputs[frames % outputs.size()];
    arena.execute([&] {
      tbb::parallel_for(size_t(0), h.chunks.size(), [&](size_t c) {
        thread_local io::DecodeScratch scratch;
        thread_local std::vector<std::byte> payload;
        // The record's payload, then its fine part (format 3.0) after it.
        io::ChunkDesc chunk = h.chunks[c];
        payload.resize(uint64_t(chunk.compressed_size) + chunk.fine.size);
        const uint64_t base = reader.index().frames[f].offset;
        const auto read = [&](uint64_t into, uint64_t from, uint64_t n) {
          if (::pread(reader.descriptor(), payload.data() + into, n, static_cast<off_t>(base + from)) != ssize_t(n)) {
            throw io::Error(reader.location(f, c), "short read");
          }
        };
        read(0, chunk.offset, chunk.compressed_size);
        if (chunk.fine.split()) read(chunk.compressed_size, chunk.fine.offset, chunk.fine.size);
        chunk.offset = 0;
        chunk.fine.offset = chunk.compressed_size;
        io::decode_chunk(payload, chunk, reader.header(), {std::span(out).subspan(first[c] * stride, chunk.particle_count * stride), {}},
                         scratch, reader.location(f, c));
      });
    });
    ++frames;
  } while (seconds_since(start) < min_seconds || frames < cycle);
  return double(frames) / seconds_since(start);
}

std::string gbps(double bytes_per_second) { return fixed(bytes_per_second / 1e9, 2); }
std::string percent(double share) { return fixed(100 * share, 0) + "%"; }
std::string threads_text(int n) { return std::to_string(n) + (n == 1 ? " thread" : " threads"); }

}  // namespace

void run_stream_bench(const StreamBenchOptions& o) {
  const io::ContainerReader reader(o.file);
  if (reader.frame_count() == 0) throw io::Error({o.file}, "has no frames to stream");
  const runtime::ThreadSplit split = runtime::default_thread_split(core_count());  // the pipeline's default
  const int cores = o.max_threads > 0 ? o.max_threads : split.decode;
  PassSetup setup;
  setup.decode_threads = cores;
  setup.read_threads = o.read_threads > 0 ? o.read_threads : split.read;
  setup.memory = o.memory ? o.memory : uint64_t(2) << 30;
  const int readers = setup.read_threads;
  const runtime::HostMemory host = runtime::read_host_memory();
  const io::LayerSet layers = o.surface ? io::LayerSet::surface() : io::LayerSet::particles();
  const Slice slice = slice_of(reader, o.frames, static_cast<uint64_t>(0.4 * double(host.available())), layers);
  const double in = slice.in_per_frame(), out = slice.out_per_frame();

  std::printf("sluice bench stream: %s%s\n", o.file.c_str(),
              o.surface ? " (surface and blobs: what a player reads of a file with layers)" : "");
  std::printf("  %llu of %llu frames (%s GB on disk), %.2f M particles/frame, %.1f MB/frame on disk, %.1f MB/frame decoded\n",
              (unsigned long long)slice.frames, (unsigned long long)reader.frame_count(), fixed(double(slice.bytes) / 1e9, 2).c_str(),
              double(slice.particles) / double(slice.frames) / 1e6, in / 1e6, out / 1e6);
  if (slice.read != slice.bytes) {
    std::printf("  the layers read take %.1f MB/frame of %.1f MB/frame of records (%s)\n", in / 1e6,
                double(slice.bytes) / double(slice.frames) / 1e6, percent(double(slice.read) / double(slice.bytes)).c_str());
  }
  std::printf("machine: %s; pipeline: %d decode workers, %s reading, memory cap %s GB; timings of at least %.1f s\n",
              cpu_model().c_str(), cores, threads_text(readers).c_str(), fixed(double(setup.memory) / (1 << 30), 1).c_str(),
              o.min_seconds);
  if (!o.frames && slice.frames < reader.frame_count()) {
    std::printf("  (only the frames that fit in 40%% of available memory, so the page-cache figures are from the cache)\n");
  }

  // 1. Bounds, read the way the pipeline reads (8 MiB pieces, its read threads).
  Table bounds({"bound", "GB/s", "frames/s of this file", "what"});
  const double copy_1 = memcpy_gbps(std::min(1.0, o.min_seconds)) * 1e9;
  const int all_cores = std::max(cores, core_count());  // the machine's bound, not the pipeline's share
  const double copy_n = parallel_memcpy_gbps(all_cores, std::min(1.0, o.min_seconds)) * 1e9;
  bounds.row({"memcpy, 1 thread", gbps(copy_1), fixed(copy_1 / out, 1), "decoded bytes"});
  bounds.row({"memcpy, " + threads_text(all_cores), gbps(copy_n), fixed(copy_n / out, 1), "decoded bytes"});
  double storage = 0, cold_share = 1;
  std::optional<double> direct;
  if (o.storage) {
    const double cold = *sequential_read_gbps(o.file, slice.offset, slice.bytes, ReadMode::BufferedCold, 0, readers) * 1e9;
    drop_from_page_cache(o.file, slice.offset, slice.bytes);
    cold_share = page_cache_share(o.file, slice.offset, slice.bytes);
    direct = sequential_read_gbps(o.file, slice.offset, slice.bytes, ReadMode::Direct, 0, readers);
    if (direct) *direct *= 1e9;
    storage = std::max(cold, direct.value_or(0));
    bounds.row({"pread, storage, cache dropped, " + threads_text(readers), gbps(cold), fixed(cold / in, 1),
                "file bytes, kernel readahead"});
    if (direct) bounds.row({"pread, storage, O_DIRECT, " + threads_text(readers), gbps(*direct), fixed(*direct / in, 1), "file bytes"});
    else bounds.row({"pread, storage, O_DIRECT", "-", "-", "refused by the filesystem"});
  }
  (void)sequential_read_gbps(o.file, slice.offset, slice.bytes, ReadMode::PageCache, 0, readers);  // bring it in
  const double warm_share = page_cache_share(o.file, slice.offset, slice.bytes);
  const double cached_1 = *sequential_read_gbps(o.file, slice.offset, slice.bytes, ReadMode::PageCache, o.min_seconds, 1) * 1e9;
  bounds.row({"pread, page cache, 1 thread", gbps(cached_1), fixed(cached_1 / in, 1), "file bytes"});
  double cached = cached_1;
  if (readers > 1) {
    cached = *sequential_read_gbps(o.file, slice.offset, slice.bytes, ReadMode::PageCache, o.min_seconds, readers) * 1e9;
    bounds.row({"pread, page cache, " + threads_text(readers), gbps(cached), fixed(cached / in, 1), "file bytes"});
  }
  const double decode_fps = decode_only_fps(reader, slice, cores, o.min_seconds);
  bounds.row({"decode only, " + std::to_string(cores) + " workers, records in memory", gbps(decode_fps * out),
              fixed(decode_fps, 1), "decoded bytes (the work itself, not a bound)"});
  const double chunked_fps = chunk_read_decode_fps(reader, slice, all_cores, o.min_seconds);
  bounds.row({"pread + decode per chunk, " + std::to_string(all_cores) + " workers, page cache", gbps(chunked_fps * out),
              fixed(chunked_fps, 1), "decoded bytes (each worker reads its own chunks; not a bound)"});
  bounds.print("Machine bounds, measured now");
  if (o.storage) std::printf("  page cache held %s of the frames after dropping them\n", percent(cold_share).c_str());
  std::printf("  page cache held %s of the frames for the page-cache passes\n", percent(warm_share).c_str());

  // 2. The pipeline, from storage and from the page cache.
  Table passes({"source", "frames/s", "M particles/s", "read GB/s", "read a frame", "device a frame", "decoded GB/s", "window",
                "bound frames/s", "vs bound", "limited by", "vs decode alone", "read path"});
  auto pass_row = [&](const std::string& name, const Pass& p, double read_bound, const std::string& read_name) {
    const double fps = double(p.frames) / p.seconds;
    const double read_fps = read_bound / in, copy_fps = copy_n / out;
    const bool read_slower = read_fps < copy_fps;
    // What storage delivered beside what was asked (readahead cannot hide):
    // about 0 from the page cache.
    const double frames = double(std::max<uint64_t>(p.frames, 1));
    const double asked = double(p.bytes_read) / frames, device = double(p.device_bytes) / frames;
    passes.row({name, fixed(fps, 1), fixed(fps * double(slice.particles) / double(slice.frames) / 1e6, 1),
                fixed(p.rates.read_mbps / 1e3, 2), fixed(asked / 1e6, 1) + " MB",
                fixed(device / 1e6, 1) + " MB" + (asked > 0 && device > 0 ? " (" + fixed(device / asked, 2) + "x)" : ""),
                fixed(p.rates.decode_mbps / 1e3, 2), p.window,
                fixed(std::min(read_fps, copy_fps), 1), percent(fps / std::min(read_fps, copy_fps)),
                read_slower ? read_name : "memcpy, " + threads_text(all_cores), percent(fps / decode_fps), p.io_mode});
    if (p.cache_hits) {
      std::printf("  warning: %s: %llu frames came from memory, not through the pipeline\n", name.c_str(),
                  (unsigned long long)p.cache_hits);
    }  };
  if (o.storage) {
    // The storage bound is the faster of the two ways of reading it.
    const std::string storage_name = "storage read";
    if (direct) {
      drop_from_page_cache(o.file, slice.offset, slice.bytes);
      pass_row("storage, O_DIRECT", stream(reader, slice, setup, true, false, 0, layers), storage, storage_name);
    }
    drop_from_page_cache(o.file, slice.offset, slice.bytes);
    pass_row("storage, cache dropped", stream(reader, slice, setup, false, false, 0, layers), storage, storage_name);
    (void)sequential_read_gbps(o.file, slice.offset, slice.bytes, ReadMode::PageCache, 0, readers);  // back into the cache
  }
  pass_row("page cache", stream(reader, slice, setup, false, true, o.min_seconds, layers), cached,
           "pread, page cache, " + threads_text(readers));
  passes.print("Pipeline: reader thread (" + threads_text(readers) + " reading) + " + std::to_string(cores) +
               " decode workers -> null consumer (bound: the slower of reading the file and memcpy)");

  // 3. Decode scaling through the pipeline.
  Table scaling({"workers", "frames/s", "decoded GB/s", "GB/s per busy worker", "workers busy", "speed-up"});
  double base = 0;
  for (int t = 1; t <= cores; t = (t == cores ? cores + 1 : std::min(cores, t * 2))) {
    PassSetup scaled = setup;
    scaled.decode_threads = t;
    const Pass p = stream(reader, slice, scaled, false, true, std::max(1.0, o.min_seconds / 2), layers);
    const double fps = double(p.frames) / p.seconds;
    if (t == 1) base = fps;
    double per_worker = 0, busy = 0;  // averages over the workers that decoded
    const auto active = double(std::max<size_t>(1, p.rates.worker_decode_mbps.size()));
    for (size_t w = 0; w < p.rates.worker_decode_mbps.size(); ++w) {
      per_worker += p.rates.worker_decode_mbps[w] / active;
      busy += p.rates.worker_busy[w] / active;
    }
    scaling.row({std::to_string(t), fixed(fps, 1), fixed(p.rates.decode_mbps / 1e3, 2), fixed(per_worker / 1e3, 2),
                 percent(busy), fixed(fps / base, 2) + "x"});
  }
  scaling.print("Decode scaling through the pipeline, page cache (" + threads_text(readers) + " reading)");
}

}  // namespace sluice::bench
