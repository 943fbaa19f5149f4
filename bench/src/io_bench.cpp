// `sluice bench io`: the same frames read by VTK's XML reader and by sluice,
// sizes on disk, and decode scaling over threads.
#include "sluice/bench/io_bench.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <algorithm>
#include <optional>
#include <random>

#include "machine.h"
#include "sluice/import/frames.h"
#include "sluice/import/freed_memory.h"
#include "sluice/import/vtk.h"
#include "sluice/io/lod.h"
#include "sluice/io/reader.h"
#include "sluice/io/point_set.h"
#include "sluice/bench/table.h"
#include "timing.h"

namespace sluice::bench {
namespace {

// The input's format as the source describes it: the text of the last
// parentheses ("VTK XML unstructured grid", "VTK legacy polydata", "CSV").
std::string input_format(const std::string& description) {
  const size_t open = description.rfind('('), close = description.rfind(')');
  if (open == std::string::npos || close == std::string::npos || close < open) return "the input's reader";
  return description.substr(open + 1, close - open - 1);
}

struct Dataset {
  std::vector<io::ParticleFrame> frames;
  uint64_t particles = 0;
  uint64_t input_bytes = 0;
};

std::string write_container(const std::string& path, const import::FrameSource& source, io::PositionCoding coding,
                            io::PlaneCoding planes = io::PlaneCoding::Packed) {
  io::FileHeader header;
  header.position_coding = coding;
  header.lod_id_array = source.info().id_array;
  header.lod_source = header.lod_id_array.empty() ? io::LodSource::ParticleOrder : io::LodSource::IdHash;
  header.source = source.info().description;
  io::ContainerWriter writer(path, header);
  io::EncodeOptions encode;
  encode.planes = planes;
  import::convert_frames(source, std::nullopt, writer, import::FramesSettings{.encode = encode, .max_in_flight = size_t(core_count()) + 1});
  writer.finish();
  return path;
}

// Every chunk of every frame of a container, records held in memory.
struct LoadedContainer {
  std::vector<std::vector<std::byte>> records;
  std::vector<io::FrameHeader> frames;
  std::vector<std::pair<size_t, size_t>> chunks;  // (frame, chunk)
  uint64_t particles = 0;
};

// The chunk list repeats until there are `min_items` work items, so that
// every thread count has enough independent chunks to keep its threads busy.
LoadedContainer load(const io::ContainerReader& reader, size_t min_items) {
  LoadedContainer c;
  for (uint64_t f = 0; f < reader.frame_count(); ++f) {
    c.records.push_back(reader.read_record(f));
    c.frames.push_back(reader.parse_record(f, c.records.back()));
  }
  while (c.chunks.size() < min_items) {
    for (uint64_t f = 0; f < reader.frame_count(); ++f) {
      for (size_t k = 0; k < c.frames[f].chunks.size(); ++k) c.chunks.emplace_back(f, k);
      c.particles += c.frames[f].particle_count;
    }
    if (c.particles == 0) break;
  }
  return c;
}

// Decodes every chunk into per-thread output buffers (as the runtime decodes
// into staging memory), with `threads` workers.
void decode_all(const io::ContainerReader& reader, const LoadedContainer& c, int threads) {
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(size_t(0), c.chunks.size(), [&](size_t i) {
      thread_local io::DecodeScratch scratch;
      thread_local std::vector<std::byte> out;
      thread_local std::vector<uint16_t> attribute;
      const auto [f, k] = c.chunks[i];
      const io::ChunkDesc& chunk = c.frames[f].chunks[k];
      out.resize(chunk.particle_count * io::decoded_particle_bytes(reader.header().position_coding));
      io::decode_chunk(c.records[f], chunk, reader.header(), {out, {}}, scratch, reader.location(f, k));
    });
  });
}

// Reads each frame from the file (page cache) and decodes it: the whole path.
void read_and_decode_all(const io::ContainerReader& reader, int threads) {
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(uint64_t(0), reader.frame_count(), [&](uint64_t f) {
      thread_local io::DecodeScratch scratch;
      thread_local std::vector<std::byte> record, out;
      record.resize(reader.index().frames[f].bytes);
      reader.read_record(f, record);
      const io::FrameHeader h = reader.parse_record(f, record);
      for (size_t k = 0; k < h.chunks.size(); ++k) {
        out.resize(h.chunks[k].particle_count * io::decoded_particle_bytes(reader.header().position_coding));
        io::decode_chunk(record, h.chunks[k], reader.header(), {out, {}}, scratch, reader.location(f, k));
      }
    });
  });
}

// `frame` `tile` times side by side along x (a tenth of its width apart),
// ids offset so that every copy's are distinct.
io::ParticleFrame tiled(const io::ParticleFrame& frame, int tile) {
  if (tile <= 1) return frame;
  float lo = 0, hi = 0;
  for (size_t i = 0; i < frame.positions.size(); i += 3) {
    lo = i == 0 ? frame.positions[i] : std::min(lo, frame.positions[i]);
    hi = i == 0 ? frame.positions[i] : std::max(hi, frame.positions[i]);
  }
  const float step = (hi - lo) * 1.1f + 1e-3f;
  const uint64_t id_step = frame.ids.empty() ? 0 : *std::max_element(frame.ids.begin(), frame.ids.end()) + 1;
  io::ParticleFrame out;
  out.attributes.resize(frame.attributes.size());
  for (int k = 0; k < tile; ++k) {
    for (size_t i = 0; i < frame.positions.size(); i += 3) {
      out.positions.push_back(frame.positions[i] + step * float(k));
      out.positions.push_back(frame.positions[i + 1]);
      out.positions.push_back(frame.positions[i + 2]);
    }
    for (uint64_t id : frame.ids) out.ids.push_back(id + id_step * uint64_t(k));
    for (size_t a = 0; a < frame.attributes.size(); ++a) {
      out.attributes[a].insert(out.attributes[a].end(), frame.attributes[a].begin(), frame.attributes[a].end());
    }
  }
  return out;
}

// The files of each frame, when every frame is one file (not pieces).
std::vector<std::string> single_files(const import::FrameSource& source) {
  std::vector<std::string> files;
  for (uint64_t f = 0; f < source.frame_count(); ++f) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(source.frame_name(f), ec)) return {};
    files.push_back(source.frame_name(f));
  }
  return files;
}

// The importer against VTK's own reader on the same files and the same
// arrays, one thread, page cache: the input as given, and copies of its
// frames written by VTK's writers (legacy binary polydata as solvers write
// it, .vtu appended raw and zlib), with every array the input has.
void compare_with_vtk(const IoBenchOptions& o, const import::FrameSource& source, const std::filesystem::path& dir) {
  if (!import::has_vtk_support()) return;
  namespace fs = std::filesystem;
  const import::SourceInfo& info = source.info();
  std::vector<std::string> rest;  // every other point array, as attributes
  for (const auto& a : info.arrays) {
    if (a != info.id_array && rest.size() < io::kMaxAttributes) rest.push_back(a);
  }
  import::SourceOptions every;
  every.attributes = rest;
  const auto all = import::open_source(o.input, every);
  const import::PeerArrays arrays{info.id_array, rest};
  for (uint64_t f = 0; f < all->frame_count(); ++f) {
    const io::ParticleFrame frame = tiled(all->read(f), o.tile);
    const std::string n = std::to_string(f);
    import::write_legacy_vtk((dir / ("legacy_" + n + ".vtk")).string(), frame, arrays);
    import::write_vtu((dir / ("raw_" + n + ".vtu")).string(), frame, false, arrays);
    import::write_vtu((dir / ("zlib_" + n + ".vtu")).string(), frame, true, arrays);
  }
  struct Flavour {
    std::string name;
    std::string spec;  // as the importer opens it
  };
  std::vector<Flavour> flavours;
  if (!single_files(source).empty()) flavours.push_back({"input as given (" + input_format(info.description) + ")", o.input});
  const std::string tiles = o.tile > 1 ? ", frames x" + std::to_string(o.tile) : "";
  flavours.push_back({"legacy binary .vtk (VTK's 4.2 polydata writer" + tiles + ")", (dir / "legacy_*.vtk").string()});
  flavours.push_back({".vtu appended raw (VTK's writer" + tiles + ")", (dir / "raw_*.vtu").string()});
  flavours.push_back({".vtu appended zlib (VTK's writer" + tiles + ")", (dir / "zlib_*.vtu").string()});

  Table t({"files", "arrays", "malloc", "VTK's reader M particles/s", "sluice import M particles/s", "import / VTK",
           "checks, % of import"});
  const std::vector<std::string> ids_only = info.id_array.empty() ? std::vector<std::string>{}
                                                                  : std::vector<std::string>{info.id_array};
  for (const Flavour& fl : flavours) {
    const auto points_ids = import::open_source(fl.spec, {});
    const auto everything = import::open_source(fl.spec, every);
    const std::vector<std::string> files = single_files(*points_ids);
    double n = 0;
    for (uint64_t f = 0; f < points_ids->frame_count(); ++f) n += double(points_ids->read(f).count());
    const double checks = seconds_per_pass(o.min_seconds, [&] {
      for (const auto& file : files) import::check_vtk_file(file);
    });
    for (const bool keep_freed : {false, true})
    for (const bool every_array : {false, true}) {
      std::optional<import::KeepFreedMemory> keep;
      if (keep_freed) keep.emplace();
      const import::FrameSource& s = every_array ? *everything : *points_ids;
      const double vtk = seconds_per_pass(o.min_seconds, [&] {
        for (const auto& file : files) (void)import::read_with_vtk(file, every_array ? nullptr : &ids_only);
      });
      const double import = seconds_per_pass(o.min_seconds, [&] {
        for (uint64_t f = 0; f < s.frame_count(); ++f) (void)s.read(f);
      });
      const bool legacy = fl.spec.size() > 4 && fl.spec.compare(fl.spec.size() - 4, 4, ".vtk") == 0;
      const std::string what = every_array ? "every array (" + std::to_string(rest.size() + !info.id_array.empty()) + ")"
                                           : std::string(info.id_array.empty() ? "points" : "points + ids") +
                                                 (legacy ? " (VTK: every array)" : "");
      t.row({fl.name, what, keep_freed ? "kept" : "default", fixed(n / vtk / 1e6, 2), fixed(n / import / 1e6, 2),
             fixed(vtk / import, 2) + "x", fixed(100.0 * checks / import, 1) + "%"});
    }
  }
  t.print("The importer against VTK's own reader: same files, same arrays, 1 thread, page cache");
  std::printf("  malloc 'default': glibc as it comes; 'kept': freed memory kept for the next frame\n"
              "  (import::KeepFreedMemory, as `sluice convert` runs), for both readers alike.\n"
              "  VTK's legacy reader cannot choose arrays: it reads every array whatever is asked.\n"
              "  'checks': the size checks alone (legacy: the structure walk with the data skipped), which\n"
              "  the import includes; XML copies hold float32 points, a UInt32 id array and float32 arrays.\n");
}

}  // namespace

void run_io_bench(const IoBenchOptions& o) {
  const int cores = o.max_threads > 0 ? o.max_threads : core_count();
  const auto source = import::open_source(o.input, {});
  const uint64_t frame_count = source->frame_count();
  std::printf("sluice bench io: %s\n", source->info().description.c_str());
  std::printf("machine: %s, %d threads; each timing repeats for at least %.1f s\n", cpu_model().c_str(), cores,
              o.min_seconds);

  // 1. VTK's reader, one thread per file as convert uses it, and one thread.
  Dataset data;
  data.frames.resize(frame_count);
  for (uint64_t f = 0; f < frame_count; ++f) {
    std::error_code ec;
    data.input_bytes += std::filesystem::file_size(source->frame_name(f), ec);
  }
  const double vtk_1 = seconds_per_pass(o.min_seconds, [&] {
    for (uint64_t f = 0; f < frame_count; ++f) data.frames[f] = source->read(f);
  });
  for (const auto& f : data.frames) data.particles += f.count();
  // VTK reading every array of each file, as ParaView opens it.
  double vtk_full = 0;
  if (import::has_vtk_support()) {
    vtk_full = seconds_per_pass(o.min_seconds, [&] {
      for (uint64_t f = 0; f < frame_count; ++f) (void)import::read_with_vtk(source->frame_name(f));
    });
  }
  const double vtk_n = seconds_per_pass(o.min_seconds, [&] {
    tbb::task_arena arena(cores);
    arena.execute([&] { tbb::parallel_for(uint64_t(0), frame_count, [&](uint64_t f) { (void)source->read(f); }); });
  });

  // 2. Files of the same frames.
  namespace fs = std::filesystem;
  const bool temp = o.work_dir.empty();
  const fs::path dir = temp ? fs::temp_directory_path() / ("sluice-bench-" + std::to_string(std::random_device{}()))
                            : fs::path(o.work_dir);
  fs::create_directories(dir);
  const std::string quantized = write_container((dir / "q.sluice").string(), *source, io::PositionCoding::Quantized16);
  const std::string lossless = write_container((dir / "f.sluice").string(), *source, io::PositionCoding::Float32);
  const std::string smallest =
      write_container((dir / "z.sluice").string(), *source, io::PositionCoding::Quantized16, io::PlaneCoding::Zstd);
  uint64_t vtu_zlib = 0, vtu_raw = 0;
  if (import::has_vtk_support()) {
    for (uint64_t f = 0; f < frame_count; ++f) {
      import::write_vtu((dir / "z.vtu").string(), data.frames[f], true);
      vtu_zlib += fs::file_size(dir / "z.vtu");
      import::write_vtu((dir / "r.vtu").string(), data.frames[f], false);
      vtu_raw += fs::file_size(dir / "r.vtu");
    }
  }
  const double n = double(data.particles);
  const io::ContainerReader q(quantized), l(lossless), z(smallest);
  const double q_bytes = double(fs::file_size(quantized)), l_bytes = double(fs::file_size(lossless));
  const double z_bytes = double(fs::file_size(smallest));
  Table sizes({"format", "bytes", "bytes/particle", "vs raw float32 xyz"});
  auto size_row = [&](const std::string& name, double bytes) {
    sizes.row({name, fixed(bytes, 0), fixed(bytes / n, 2), fixed(12.0 * n / bytes, 2) + "x smaller"});
  };
  size_row("raw float32 xyz (no LOD value)", 12.0 * n);
  size_row("input files (as given)", double(data.input_bytes));
  if (vtu_raw) size_row("VTK .vtu float32, appended raw", double(vtu_raw));
  if (vtu_zlib) size_row("VTK .vtu float32, zlib", double(vtu_zlib));
  size_row(".sluice lossless float32 + LOD", l_bytes);
  size_row(".sluice quantized 16-bit + LOD", q_bytes);
  size_row(".sluice quantized, zstd on every plane (--smallest)", z_bytes);
  std::printf("\n%llu frames, %llu particles in all (%.0f per frame), spacing %.4g\n", (unsigned long long)frame_count,
              (unsigned long long)data.particles, n / double(frame_count),
              io::estimate_spacing(data.frames[0].positions));
  sizes.print("Size on disk (LOD value included in .sluice; VTK files carry no LOD value)");

  // 3. Read + decode against VTK's reader, page cache.
  const double out_bytes = n * 8;
  const double rd_1 = seconds_per_pass(o.min_seconds, [&] { read_and_decode_all(q, 1); });
  const double rd_n = seconds_per_pass(o.min_seconds, [&] { read_and_decode_all(q, cores); });
  const double rdl_n = seconds_per_pass(o.min_seconds, [&] { read_and_decode_all(l, cores); });
  const double rdz_1 = seconds_per_pass(o.min_seconds, [&] { read_and_decode_all(z, 1); });
  Table read({"reader", "threads", "M particles/s", "input MB/s", "output GB/s", "vs VTK (same threads)"});
  if (vtk_full > 0) {
    read.row({"VTK's own reader, every array (as ParaView), 1 thread", "1", fixed(n / vtk_full / 1e6, 2),
              fixed(double(data.input_bytes) / vtk_full / 1e6, 1), fixed(n * 12 / vtk_full / 1e9, 3), "-"});
  }
  // Every row names what it measured, once: the reader (from the input's
  // format, e.g. "VTK legacy polydata") and the thread count.
  const std::string format = input_format(source->info().description);
  const auto threads = [](int t) { return t == 1 ? std::string(", 1 thread") : ", " + std::to_string(t) + " threads"; };
  read.row({"sluice import, " + format + " (points + ids)" + threads(1), "1", fixed(n / vtk_1 / 1e6, 2),
            fixed(double(data.input_bytes) / vtk_1 / 1e6, 1), fixed(n * 12 / vtk_1 / 1e9, 3), "1.0x"});
  read.row({"sluice import, " + format + " (points + ids)" + threads(cores), std::to_string(cores), fixed(n / vtk_n / 1e6, 2),
            fixed(double(data.input_bytes) / vtk_n / 1e6, 1), fixed(n * 12 / vtk_n / 1e9, 3), "1.0x"});
  read.row({".sluice quantized read+decode" + threads(1), "1", fixed(n / rd_1 / 1e6, 1), fixed(q_bytes / rd_1 / 1e6, 1),
            fixed(out_bytes / rd_1 / 1e9, 2), fixed(vtk_1 / rd_1, 0) + "x"});
  read.row({".sluice quantized --smallest read+decode" + threads(1), "1", fixed(n / rdz_1 / 1e6, 1), fixed(z_bytes / rdz_1 / 1e6, 1),
            fixed(out_bytes / rdz_1 / 1e9, 2), fixed(vtk_1 / rdz_1, 0) + "x"});
  read.row({".sluice quantized read+decode" + threads(cores), std::to_string(cores), fixed(n / rd_n / 1e6, 1),
            fixed(q_bytes / rd_n / 1e6, 1), fixed(out_bytes / rd_n / 1e9, 2), fixed(vtk_n / rd_n, 0) + "x"});
  read.row({".sluice lossless read+decode" + threads(cores), std::to_string(cores), fixed(n / rdl_n / 1e6, 1),
            fixed(l_bytes / rdl_n / 1e6, 1), fixed(n * 16 / rdl_n / 1e9, 2), fixed(vtk_n / rdl_n, 0) + "x"});
  read.print("Read + decode from the page cache (output: 8 B/particle quantized, 16 B lossless; VTK: float32 xyz)");
  std::printf("  'sluice import' reads only the points and the id array (its own reader for legacy and text\n"
              "  files, VTK's XML readers for .vtu/.vtp); .sluice read+decode against VTK reading every\n"
              "  array, one thread: %.0fx\n",
              vtk_full > 0 ? vtk_full / rd_1 : 0.0);
  compare_with_vtk(o, *source, dir);

  // 4. Decode scaling, records in memory.
  const LoadedContainer loaded = load(q, size_t(16 * cores));
  Table scaling({"threads", "M particles/s", "output GB/s", "GB/s per thread", "speed-up"});
  double base = 0;
  for (int t = 1; t <= cores; t = (t == cores ? cores + 1 : std::min(cores, t * 2))) {
    const double s = seconds_per_pass(o.min_seconds, [&] { decode_all(q, loaded, t); });
    const double gbps = double(loaded.particles) * 8 / s / 1e9;
    if (t == 1) base = gbps;
    scaling.row({std::to_string(t), fixed(double(loaded.particles) / s / 1e6, 1), fixed(gbps, 2), fixed(gbps / t, 2),
                 fixed(gbps / base, 2) + "x"});
  }
  scaling.print("Decode scaling, quantized chunks in memory (" + std::to_string(loaded.chunks.size()) +
                " chunk decodes per pass; the file's chunks repeated so every thread has work)");
  std::printf("\nmemcpy bound, one thread: %.1f GB/s\n", memcpy_gbps(o.min_seconds));
  if (temp) fs::remove_all(dir);
}

}  // namespace sluice::bench
