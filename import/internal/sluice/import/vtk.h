// sluice/import/vtk.h: VTK's own readers and writers, for comparisons
// (`sluice bench io`, the peer in tests) and for hosts that vet files.
//
// Errors: throws io::Error naming the file. Threads: any, one call per file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sluice/io/types.h"

namespace sluice::import {

// True when this build reads (and writes) VTK files.
bool has_vtk_support();

// The peer's files of a frame, for comparisons: every file holds float32
// points, `id_name` (if not empty) as a UInt32/unsigned_int id array from
// frame.ids, and the attributes under `attribute_names` (float32 scalars).
struct PeerArrays {
  std::string id_name;
  std::vector<std::string> attribute_names;  // one per frame.attributes
};

// A VTK XML unstructured grid with one VTK_VERTEX cell per particle (as
// solvers write particle files), appended binary data, zlib-compressed when
// `compress`. Throws io::Error when built without VTK.
void write_vtu(const std::string& path, const io::ParticleFrame& frame, bool compress, const PeerArrays& arrays = {});

// A legacy binary POLYDATA file written by VTK's own writer in the 4.2
// layout solvers write (one vertex per particle). Throws io::Error when
// built without VTK.
void write_legacy_vtk(const std::string& path, const io::ParticleFrame& frame, const PeerArrays& arrays);

// Reads a VTK file with VTK's own reader and returns its point count: the
// peer in `sluice bench io`. `only` null: every array, as ParaView opens
// it; otherwise only those point arrays (XML readers; VTK's legacy reader
// cannot choose and reads every array). Throws io::Error when built without
// VTK.
uint64_t read_with_vtk(const std::string& path, const std::vector<std::string>* only = nullptr);

// The checks read() makes of a VTK file before it is read (declared sizes
// against the bytes present; for legacy files the whole structure, with the
// data skipped). Throws the io::Error read() would. For measuring what the
// checks cost, and for hosts that vet files before accepting them.
void check_vtk_file(const std::string& path);

}  // namespace sluice::import
