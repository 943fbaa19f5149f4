// `sluice info`: what a .sluice file holds, for people or (--json) scripts.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <tuple>
#include <vector>

#include "commands.h"
#include "human.h"
#include "json_text.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/reader.h"

namespace sluice::app {
namespace {

struct InfoOptions {
  std::string file;
  bool json = false;
  bool all_frames = false;
  std::optional<uint64_t> records;  // --records FRAME
};

const char* coding_name(io::PositionCoding c) {
  return c == io::PositionCoding::Quantized16 ? "quantized16" : "float32";
}

const char* evidence_text(io::UpEvidence e) {
  switch (e) {
    case io::UpEvidence::Given: return "given at conversion";
    case io::UpEvidence::Motion: return "found from the fluid's fall over the first frames";
    case io::UpEvidence::Pressure: return "found from pressure growing with depth";
    case io::UpEvidence::Shape: return "found from the fluid lying flat; its sign assumed";
    case io::UpEvidence::Default: return "assumed: the data did not show it";
    default: return "not stated (a file older than format 1.2)";
  }
}

// Where players decode the file's frames, from frame 0's plane tables:
// what the GPU decodes as it lies on disk and what the CPU inflates first.
std::string decoding_text(const io::ContainerReader& r) {
  if (!io::gpu_decodable(r.header())) return "on the CPU (float32 positions)";
  // The census reads the whole record: skipped where that is a lot to read for a summary.
  constexpr uint64_t kMostCensusBytes = uint64_t(64) << 20;
  if (r.index().frames.empty() || r.index().frames[0].bytes > kMostCensusBytes) return "on the GPU by default (--decode)";
  io::GpuDecodePlan plan;
  try {
    const std::vector<std::byte> record = r.read_record(0);
    const io::FrameHeader header = r.parse_record(0, record);
    io::plan_gpu_decode(record, header, r.header(), {.color_attribute = r.header().attributes.empty() ? -1 : 0}, plan,
                        r.location(0));
  } catch (const io::Error& e) {
    return std::string("on the CPU (frame 0 cannot be planned for the GPU: ") + e.what() + ")";
  }
  const uint64_t planes = plan.stored_planes + plan.packed_planes + plan.zstd_planes;
  std::string text = "on the GPU by default (--decode); frame 0's planes: " + std::to_string(plan.stored_planes) +
                     " stored, " + std::to_string(plan.packed_planes) + " bit-packed";
  if (plan.zstd_planes == 0) return text + ", none to inflate on the CPU";
  return text + ", " + std::to_string(plan.zstd_planes) + " zstd (" + percent(double(plan.zstd_planes) / double(planes)) +
         ", inflated on the CPU first; `sluice convert --gpu-decodable` writes none)";
}

// Median seconds of simulation between frames (0 with fewer than 2 frames).
double median_step(const std::vector<io::FrameIndexEntry>& frames) {
  std::vector<double> steps;
  for (size_t i = 1; i < frames.size(); ++i) steps.push_back(frames[i].time - frames[i - 1].time);
  if (steps.empty()) return 0;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2];
}

std::string json_box(const io::Aabb& b) {
  if (b.empty()) return "null";
  return "{\"min\": [" + json_number(b.min[0]) + ", " + json_number(b.min[1]) + ", " + json_number(b.min[2]) +
         "], \"max\": [" + json_number(b.max[0]) + ", " + json_number(b.max[1]) + ", " + json_number(b.max[2]) + "]}";
}

std::string text_box(const io::Aabb& b) {
  if (b.empty()) return "(empty)";
  char buf[160];
  std::snprintf(buf, sizeof buf, "[%.4g, %.4g, %.4g] .. [%.4g, %.4g, %.4g]", b.min[0], b.min[1], b.min[2], b.max[0],
                b.max[1], b.max[2]);
  return buf;
}

void print_json(const io::ContainerReader& r) {
  const io::FileHeader& h = r.header();
  const auto& frames = r.index().frames;
  uint64_t particles = 0;
  for (const auto& f : frames) particles += f.count_in(io::LayerSet::particles());
  std::printf("{\n  \"file\": %s,\n  \"format_version\": \"%u.%u\",\n  \"layout\": \"%s\",\n  \"file_bytes\": %llu,\n",
              json_string(r.path()).c_str(), h.version_major, h.version_minor,
              h.version_major >= 3 ? "coarse_to_fine_split" : h.version_major == 2 ? "coarse_to_fine" : "cells",
              (unsigned long long)r.file_size());
  std::printf("  \"position_coding\": \"%s\",\n  \"lod_source\": \"%s\",\n  \"lod_id_array\": %s,\n", coding_name(h.position_coding),
              h.lod_source == io::LodSource::IdHash ? "id_hash" : "particle_order", json_string(h.lod_id_array).c_str());
  std::printf("  \"particle_spacing\": %s,\n  \"particle_radius\": %s,\n  \"frame_rate\": %s,\n  \"source\": %s,\n",
              json_number(h.particle_spacing).c_str(), json_number(h.particle_radius).c_str(),
              json_number(h.frame_rate).c_str(), json_string(h.source).c_str());
  std::printf("  \"precision_bits\": %u,\n  \"position_bound\": %s,\n", unsigned(h.precision_bits),
              std::isfinite(io::position_bound(h)) ? json_number(io::position_bound(h)).c_str() : "null");
  std::printf("  \"up\": \"%s\",\n  \"up_evidence\": \"%s\",\n  \"time_source\": \"%s\",\n",
              io::up_axis_name(h.up).c_str(), io::up_evidence_name(h.up_evidence), io::time_source_name(h.time_source));
  std::printf("  \"bounds\": %s,\n  \"attributes\": [", json_box(r.index().bounds).c_str());
  for (size_t a = 0; a < h.attributes.size(); ++a) {
    std::printf("%s{\"name\": %s, \"min\": %s, \"max\": %s}", a ? ", " : "", json_string(h.attributes[a].name).c_str(),
                json_number(r.index().attribute_ranges[a][0]).c_str(), json_number(r.index().attribute_ranges[a][1]).c_str());
  }
  std::printf("],\n  \"frame_count\": %zu,\n  \"particles_total\": %llu,\n  \"frames\": [\n", frames.size(),
              (unsigned long long)particles);
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto& f = frames[i];
    std::printf("    {\"frame\": %zu, \"time\": %s, \"particles\": %llu, \"chunks\": %u, \"offset\": %llu, \"bytes\": %llu, "
                "\"bounds\": %s, \"layers\": {\"all\": %llu, \"surface\": %llu, \"interior\": %llu, \"blobs\": %llu}}%s\n",
                i, json_number(f.time).c_str(), (unsigned long long)f.count_in(io::LayerSet::particles()), f.chunk_count,
                (unsigned long long)f.offset, (unsigned long long)f.bytes, json_box(f.bounds).c_str(),
                (unsigned long long)f.layer_particles[0], (unsigned long long)f.layer_particles[1],
                (unsigned long long)f.layer_particles[2], (unsigned long long)f.layer_particles[3],
                i + 1 < frames.size() ? "," : "");
  }
  std::printf("  ]\n}\n");
}

// What a player reading the surface and blobs reads of a frame, against the
// whole record (from the chunk table).
struct LayerBytes {
  uint64_t surface = 0, whole = 0;
};
LayerBytes layer_bytes(const io::ContainerReader& r, uint64_t frame) {
  const io::FrameHeader h = r.read_table(frame);
  return {io::layers_end(h, io::LayerSet::surface(), r.header().attributes.size()), h.frame_bytes};
}

void print_text(const io::ContainerReader& r, bool all_frames) {
  const io::FileHeader& h = r.header();
  const auto& frames = r.index().frames;
  uint64_t particles = 0, frame_bytes = 0, chunks = 0, lo = UINT64_MAX, hi = 0;
  bool layered = false;
  uint64_t surface = 0, blobs = 0;
  for (const auto& f : frames) {
    const uint64_t n = f.count_in(io::LayerSet::particles());
    particles += n;
    frame_bytes += f.bytes;
    chunks += f.chunk_count;
    lo = std::min(lo, n);
    hi = std::max(hi, n);
    layered = layered || f.layered();
    surface += f.layer_particles[size_t(io::Layer::Surface)];
    blobs += f.layer_particles[size_t(io::Layer::Blobs)];
  }
  const double per = particles ? double(frame_bytes) / double(particles) : 0;
  const size_t decoded = io::decoded_particle_bytes(h.position_coding) + 2 * h.attributes.size();
  std::printf("%s\n", r.path().c_str());
  std::printf("  format        %u.%u (%s), %s positions, %s\n", h.version_major, h.version_minor,
              h.version_major >= 3   ? "frames ordered coarse to fine, positions in two parts"
              : h.version_major == 2 ? "frames ordered coarse to fine"
                                     : "each cell's tiers together",
              h.position_coding == io::PositionCoding::Quantized16 ? "16-bit quantized" : "float32 (lossless)",
              human_bytes(double(r.file_size())).c_str());
  std::printf("  source        %s\n", h.source.c_str());
  std::printf("  LOD values    %s\n", h.lod_source == io::LodSource::IdHash
                                         ? ("hash of id array '" + h.lod_id_array + "' (stable across frames)").c_str()
                                         : "hash of particle order (stable only if the source keeps its order)");
  std::printf("  spacing       %g (radius %g)\n", h.particle_spacing, h.particle_radius);
  std::printf("  precision     %s\n", precision_text(h).c_str());
  std::printf("  up            %s (%s)\n", io::up_axis_name(h.up).c_str(), evidence_text(h.up_evidence));
  std::printf("  bounds        %s\n", text_box(r.index().bounds).c_str());
  for (size_t a = 0; a < h.attributes.size(); ++a) {
    std::printf("  attribute     %s  [%g, %g]\n", h.attributes[a].name.c_str(), r.index().attribute_ranges[a][0],
                r.index().attribute_ranges[a][1]);
  }
  if (frames.empty()) {
    std::printf("  frames        0\n");
    return;
  }
  const double step = median_step(frames);
  if (h.time_source == io::TimeSource::FrameNumber) {
    std::printf("  frames        %zu, no simulation times (convert with --dt or --fps to give them); played at %g frames/s\n",
                frames.size(), h.frame_rate);
  } else {
    std::printf("  frames        %zu, time %g .. %g s%s, every %g s; played at %g frames/s = %sx simulation speed\n",
                frames.size(), frames.front().time, frames.back().time,
                h.time_source == io::TimeSource::Step ? " (step given at conversion)" : "", step, h.frame_rate,
                step > 0 ? fixed(step * h.frame_rate, 3).c_str() : "?");
  }
  std::printf("  particles     %s per frame (min %s, max %s), %s in all\n",
              human_count(double(particles) / double(frames.size())).c_str(), human_count(double(lo)).c_str(),
              human_count(double(hi)).c_str(), human_count(double(particles)).c_str());
  if (layered) {
    std::printf("  layers        surface (narrow band) %s of the particles; the interior as %s voxel blobs per frame\n"
                "                (%s particles each); players read the surface and blobs unless asked for all\n",
                percent(double(surface) / double(std::max<uint64_t>(particles, 1))).c_str(),
                human_count(double(blobs) / double(frames.size())).c_str(),
                fixed(double(particles - surface) / double(std::max<uint64_t>(blobs, 1)), 1).c_str());
  } else {
    std::printf("  layers        none (every particle in one layer; `sluice convert` classifies the narrow band)\n");
  }
  std::printf("  chunks        %s per frame on average\n", fixed(double(chunks) / double(frames.size()), 1).c_str());
  std::printf("  compression   %s bytes/particle on disk; %sx smaller than raw float32 xyz, %sx smaller than decoded (%zu B)\n",
              fixed(per, 2).c_str(), fixed(per > 0 ? 12.0 / per : 0, 2).c_str(),
              fixed(per > 0 ? double(decoded) / per : 0, 2).c_str(), decoded);
  std::printf("  decoding      %s\n", decoding_text(r).c_str());
  if (layered) {
    std::printf("\n  %6s %10s %12s %10s %8s %7s %10s %10s  %s\n", "frame", "time", "particles", "surface", "blobs", "chunks",
                "bytes", "read", "bounds");
  } else {
    std::printf("\n  %6s %10s %12s %7s %10s  %s\n", "frame", "time", "particles", "chunks", "bytes", "bounds");
  }
  const size_t n = frames.size();
  for (size_t i = 0; i < n; ++i) {
    if (!all_frames && n > 12 && i == 5) {
      std::printf("  %6s  ... %zu more (--all-frames lists every frame)\n", "", n - 10);
      i = n - 5;
    }
    const auto& f = frames[i];
    const std::string count = human_count(double(f.count_in(io::LayerSet::particles())));
    if (!layered) {
      std::printf("  %6zu %10.4g %12s %7u %10s  %s\n", i, f.time, count.c_str(), f.chunk_count,
                  human_bytes(double(f.bytes)).c_str(), text_box(f.bounds).c_str());
      continue;
    }
    // "read": what the surface and blobs take of the record, by default all a player reads.
    const LayerBytes b = layer_bytes(r, i);
    std::printf("  %6zu %10.4g %12s %10s %8s %7u %10s %10s  %s\n", i, f.time, count.c_str(),
                human_count(double(f.layer_particles[size_t(io::Layer::Surface)])).c_str(),
                human_count(double(f.layer_particles[size_t(io::Layer::Blobs)])).c_str(), f.chunk_count,
                human_bytes(double(f.bytes)).c_str(),
                (human_bytes(double(b.surface)) + " " + percent(double(b.surface) / double(std::max<uint64_t>(b.whole, 1)))).c_str(),
                text_box(f.bounds).c_str());
  }
}

// One frame's records by layer and tier span: how many, how many
// particles, bytes, and how wide their boxes are (what a view's read can
// leave out: docs/format.md, "Layout of a frame").
void print_records(const io::ContainerReader& r, uint64_t frame) {
  if (frame >= r.frame_count()) {
    throw std::runtime_error("--records: no frame " + std::to_string(frame) + " (the file has " +
                             std::to_string(r.frame_count()) + ")");
  }
  const io::FrameHeader h = r.read_table(frame);
  struct Span {
    uint64_t records = 0, particles = 0, bytes = 0, fine = 0;
    double widest = 0, width_sum = 0;
  };
  // (the layer's place in a frame: all or surface, blobs, interior; first tier, last tier)
  const auto place = [](io::Layer l) { return l == io::Layer::Blobs ? 1 : l == io::Layer::Interior ? 2 : 0; };
  std::map<std::tuple<int, int, int, int>, Span> spans;
  for (const io::ChunkDesc& c : h.chunks) {
    Span& s = spans[{place(c.layer), int(c.layer), int(c.tier), int(c.last_tier)}];
    double width = 0;
    for (int a = 0; a < 3; ++a) width = std::max<double>(width, c.bounds.max[size_t(a)] - c.bounds.min[size_t(a)]);
    ++s.records;
    s.particles += c.particle_count;
    s.bytes += c.compressed_size;
    s.fine += c.fine.size;
    s.widest = std::max(s.widest, width);
    s.width_sum += width;
  }
  std::printf("%s frame %llu: %zu records, %s (layout %s)\n", r.path().c_str(), (unsigned long long)frame, h.chunks.size(),
              human_bytes(double(h.frame_bytes)).c_str(),
              h.split_positions ? "coarse to fine, positions in two parts, 3.0"
              : h.coarse_to_fine ? "coarse to fine, 2.0"
                                 : "cells, 1.x");
  // "bytes": the records (what a far view reads); "fine": their fine parts (format 3.0).
  std::printf("  %-9s %-6s %8s %12s %10s %10s %10s %12s %12s\n", "layer", "tiers", "records", "particles", "bytes", "fine",
              "mean rec", "widest box", "mean box");
  for (const auto& [key, s] : spans) {
    const auto [order, layer, first, last] = key;
    const std::string tiers = first == last ? std::to_string(first) : std::to_string(first) + "-" + std::to_string(last);
    std::printf("  %-9s %-6s %8llu %12s %10s %10s %10s %12s %12s\n", io::layer_name(io::Layer(layer)), tiers.c_str(),
                (unsigned long long)s.records, human_count(double(s.particles)).c_str(), human_bytes(double(s.bytes)).c_str(),
                s.fine > 0 ? human_bytes(double(s.fine)).c_str() : "-",
                human_bytes(double(s.bytes) / double(s.records)).c_str(), fixed(s.widest, 3).c_str(),
                fixed(s.width_sum / double(s.records), 3).c_str());
  }
}

}  // namespace

void add_info(CLI::App& app) {
  auto o = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand("info", "Show what a .sluice file holds: header, frames, compression");
  cmd->add_option("file", o->file, ".sluice file")->required();
  cmd->add_flag("--json", o->json, "Print JSON for scripts (every frame)");
  cmd->add_flag("--all-frames", o->all_frames, "List every frame, not the first and last five");
  cmd->add_option("--records", o->records,
                  "One frame's records by layer and LOD tier span: count, particles, bytes, box widths (what reading\n"
                  "by the view can leave out)")
      ->type_name("FRAME");
  cmd->callback([o] {
    const io::ContainerReader reader(o->file);
    if (o->records) print_records(reader, *o->records);
    else if (o->json) print_json(reader);
    else print_text(reader, o->all_frames);
  });
}

}  // namespace sluice::app
