// sluice/io/export.h: frames out of a container, into files other tools read
// (ParaView, Blender, spreadsheets): VTK XML PolyData (.vtp) with a .pvd
// collection for series, CSV and binary PLY.
//
// Plain functions over caller-owned data; no VTK needed (the .vtp writer
// writes the XML by hand, read back by VTK 9's vtkXMLPolyDataReader).
// Every writer writes `path`.partial and renames it onto `path` when the file
// is complete, so a failed export never leaves a truncated file under the
// real name. Writers are thread-safe for different paths.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

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

}  // namespace sluice::io
