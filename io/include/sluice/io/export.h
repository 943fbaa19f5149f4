// sluice/io/export.h: frames out of a container, into files other tools read
// (ParaView, Blender, spreadsheets): VTK XML PolyData (.vtp) with a .pvd
// collection for series, CSV and binary PLY; a file's frames written out
// one file each (what `sluice export` and the Python module do).
//
// Plain functions over caller-owned data; no VTK needed (the .vtp writer
// writes the XML by hand, read back by VTK 9's vtkXMLPolyDataReader).
// Every writer writes `path`.partial and renames it onto `path` when the file
// is complete, so a failed export never leaves a truncated file under the
// real name. Writers are thread-safe for different paths.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/format.h"
#include "sluice/io/reader.h"

namespace sluice::io {

// One frame's particles in plain arrays, as the writers take them.
struct ExportFrame {
  std::vector<float> positions;                 // x,y,z interleaved, world units
  std::vector<uint16_t> lod;                    // stable 16-bit LOD value per particle (lod.h)
  std::vector<std::string> attribute_names;     // one per entry of `attributes`
  std::vector<std::vector<float>> attributes;   // per attribute, per particle, in attribute units
  double time = 0.0;                            // simulation time, seconds

  uint64_t count() const { return lod.size(); }
};

// The particles of a decoded frame of a file with header `header`: positions
// in world units (dequantized exactly as the renderer does), LOD values, and
// the attributes `attributes` (indices into header.attributes, in that
// order) dequantized against each chunk's range. Particles keep the decoded
// order (chunk by chunk). Throws io::Error if an index is out of range.
ExportFrame to_export_frame(const DecodedFrame& frame, const FileHeader& header, std::span<const size_t> attributes);

// Thinning by LOD value: the renderer's cLOD rule (render/lod.h,
// shaders/cull_particles.comp) for a particle of importance w = 1,
//     keep  <=>  -ln(1 - u) >= -ln(level),   u = (value + 0.5) / 65536,
// so `level` is the fraction kept (level 1 keeps all, 0 none): LOD values
// are uniform hashes of the particle ids, so the kept particles are spread
// uniformly and are the same particles in every frame. Same float arithmetic
// as render::lod_keep(level, 1, u).
bool lod_keeps(uint16_t value, float level);

// Removes the particles lod_keeps(value, level) rejects, keeping the order.
void thin_by_lod(ExportFrame& frame, float level);

enum class ExportFormat { Vtp, Csv, Ply };

// The format named by a path's extension (.vtp, .csv, .ply; any case);
// nullopt for any other.
std::optional<ExportFormat> export_format_of(const std::string& path);

// Writers. Each writes `frame` to `path` (replacing it) and returns the bytes
// written. Attribute names must be unique and none may be `lod`, `x`, `y` or
// `z` (any case), which the writers use themselves. Throws io::Error naming
// `path` on an invalid frame or any I/O failure (with the system's reason).
//
// .vtp: VTK XML PolyData 1.0, little-endian, UInt64 headers; float32 Points,
// one vertex cell per particle (Int64 connectivity/offsets), point arrays
// `lod` (UInt16) and every attribute (Float32; the first is the active
// scalars, else `lod`), FieldData TimeValue (Float64) = frame.time; raw
// binary appended data.
uint64_t write_vtp(const std::string& path, const ExportFrame& frame);
// .csv: header `x,y,z,lod,<attributes>`, one row per particle; floats in the
// shortest form that reads back to the same float32. Names holding a comma,
// a quote or white space are quoted. The time is not stored.
uint64_t write_csv(const std::string& path, const ExportFrame& frame);
// .ply: binary_little_endian 1.0, `element vertex N` with float x, y, z,
// ushort lod and a float per attribute (white space in names becomes '_');
// the time is in a `comment time <seconds>` line.
uint64_t write_ply(const std::string& path, const ExportFrame& frame);
// Dispatches on `format`.
uint64_t write_export(const std::string& path, const ExportFrame& frame, ExportFormat format);

// One member of a .pvd collection.
struct PvdEntry {
  double time = 0.0;  // written so that it reads back as the same double
  std::string file;   // as ParaView resolves it: relative to the .pvd's directory
};

// A VTK collection (.pvd) listing `entries` in order, one DataSet each.
// Returns the bytes written; throws io::Error naming `path` on I/O failure.
uint64_t write_pvd(const std::string& path, std::span<const PvdEntry> entries);

// Series: frames of a .sluice file written out one file
// each with the writers above, and a .pvd collection for a .vtp series:
// what `sluice export` and the Python module's sluice.export() do.
//
// Frames are decoded, thinned and written in parallel (TBB), a bounded
// number at a time (one per core, fewer for big frames); the progress
// callback and the .pvd follow frame order. Each file is written as
// `path`.partial and renamed when complete (export.h), and the .pvd last,
// so a series cut short never has an index that says it is whole.
//
// Threads: export_series() blocks its caller; the callback runs on one
// thread at a time, in frame order. Errors: io::Error naming the path or
// the frame; OutputsExist before anything is written.

struct SeriesOptions {
  // The output: a file (one frame), a series name (several frames: out.vtp
  // -> out_00002.vtp ... by the file's frame numbers, and out.pvd), or a
  // printf pattern with one integer conversion (frames/shot_%04d.vtp; the
  // collection is then frames/shot.pvd). The extension picks the format.
  std::string out;
  std::vector<uint64_t> frames;         // file frame numbers, in the order written; empty: every frame
  float lod_level = 1;                  // the fraction kept by the stable LOD value (export.h: lod_keeps)
  std::vector<std::string> attributes;  // names; empty: every attribute of the file
  bool force = false;                   // replace outputs that exist
};

// Where each frame goes, and the .pvd that lists them (empty: none).
struct SeriesPlan {
  ExportFormat format = ExportFormat::Vtp;
  std::map<uint64_t, std::string> files;  // by frame number
  std::string pvd;
};
// Throws io::Error for an output whose extension names no format, or a
// pattern without exactly one integer conversion.
SeriesPlan plan_series(const std::string& out, std::span<const uint64_t> frames);

// Outputs that exist and were not to be replaced (SeriesOptions::force):
// `what()` names the first.
class OutputsExist : public Error {
 public:
  explicit OutputsExist(std::vector<std::string> paths);
  const std::vector<std::string>& paths() const noexcept { return paths_; }

 private:
  std::vector<std::string> paths_;
};

struct SeriesProgress {
  uint64_t frames_done = 0, frames = 0;
  uint64_t bytes_in = 0, bytes_out = 0;  // records read, files written
};

struct SeriesSummary {
  SeriesPlan plan;
  uint64_t frames = 0;
  uint64_t particles = 0, kept = 0;  // before and after the LOD level
  uint64_t bytes_in = 0, bytes_out = 0;
};

SeriesSummary export_series(const ContainerReader& reader, const SeriesOptions& options,
                            const std::function<void(const SeriesProgress&)>& progress = {});

}  // namespace sluice::io
