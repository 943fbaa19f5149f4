// `--layers surface|all` of play and render: which layers of a file with
// the narrow band (format 1.3) are read, decoded and drawn.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "sluice/io/format.h"
#include "sluice/io/reader.h"

namespace sluice::app {

// Adds the option to `cmd`, writing "surface" or "all" into `value`.
void add_layers_option(CLI::App& cmd, std::string& value);
// The set `value` names.
io::LayerSet layer_set(const std::string& value);
// Whether frames without layers are classified on the GPU
// (render::RendererOptions::classify_unlayered): with "surface".
bool classify_unlayered(const std::string& value);
// For the HUD and logs: "surface 7,248 + 264 blobs", "all 9,360 particles",
// "all 9,360 particles (the file has no layers)" or "surface of 9,360
// particles, classified on the GPU (the file has no layers)" for `frame`.
std::string layers_text(const io::ContainerReader& reader, uint64_t frame, io::LayerSet set);

}  // namespace sluice::app
