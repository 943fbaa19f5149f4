#include "sluice/stream/live_source.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "sluice/io/lod.h"
#include "sluice/io/writer.h"
#include "sluice/error.h"
#include "sluice/render/load.h"

namespace sluice::stream {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

render::SceneInfo live_scene(const render::Bounds& bounds, const LiveOptions& options,
                             std::vector<std::array<float, 2>> attribute_ranges, uint64_t max_particles) {
  render::SceneInfo s;
  s.bounds = bounds;
  s.particle_spacing = options.particle_spacing;
  s.particle_radius = options.particle_radius;
  const std::array<float, 3> up = io::up_vector(options.up);
  s.up = {up[0], up[1], up[2]};
  s.coding = io::PositionCoding::Quantized16;
  s.attribute_names = options.attributes;
  attribute_ranges.resize(options.attributes.size(), {0.0f, 1.0f});
  s.attribute_ranges = std::move(attribute_ranges);
  s.max_particles = max_particles;
  return s;
}

LiveSource::LiveSource(render::Renderer& renderer, const LiveOptions& options)
    : renderer_(renderer), options_(options) {
  if (renderer.scene().coding != io::PositionCoding::Quantized16) {
    throw render::Error("live frames are quantized: make the renderer with live_scene()");
  }
  if (renderer.scene().attribute_names != options.attributes) {
    throw render::Error("live source: the renderer's scene has other attributes than the options");
  }
  header_.particle_spacing = options.particle_spacing;
  header_.particle_radius = options.particle_radius;
  header_.frame_rate = options.frame_rate;
  header_.up = options.up;
  header_.up_evidence = io::UpEvidence::Given;
  header_.time_source = io::TimeSource::Input;  // the times pushed with the frames
  if (options.particle_spacing > 0) header_.precision_bits = io::kDefaultPrecisionBits;
  header_.lod_source = options.ids ? io::LodSource::IdHash : io::LodSource::ParticleOrder;
  if (options.ids) header_.lod_id_array = "ids pushed with each frame";
  for (const std::string& name : options.attributes) header_.attributes.push_back({name});
  header_.source = "live frames pushed through sluice::stream::LiveSource";
  if (!options.record.empty()) writer_ = std::make_unique<io::ContainerWriter>(options.record, header_);
  // Frames that are only decoded, not kept, need no compression.
  if (!writer_) options_.encode.planes = io::PlaneCoding::Stored;
}

LiveSource::~LiveSource() = default;

uint64_t LiveSource::push(const LiveFrame& frame) {
  const std::string what = "live frame " + std::to_string(pushed_) + ": ";
  if (frame.positions.size() % 3 != 0) throw render::Error(what + "positions are not x,y,z triples");
  const uint64_t n = frame.positions.size() / 3;
  if (options_.ids && frame.ids.size() != n) {
    throw render::Error(what + std::to_string(frame.ids.size()) + " ids for " + std::to_string(n) +
                        " particles (the source was declared with ids: LiveOptions::ids)");
  }
  if (!options_.ids && !frame.ids.empty()) {
    throw render::Error(what + "ids given to a source declared without them (LiveOptions::ids = false)");
  }
  if (!frame.attributes.empty() && frame.attributes.size() != header_.attributes.size()) {
    throw render::Error(what + std::to_string(frame.attributes.size()) + " attributes for the " +
                        std::to_string(header_.attributes.size()) + " declared");
  }
  for (size_t a = 0; a < frame.attributes.size(); ++a) {
    if (frame.attributes[a].size() != n) {
      throw render::Error(what + "attribute " + header_.attributes[a].name + " has " +
                          std::to_string(frame.attributes[a].size()) + " values for " + std::to_string(n) +
                          " particles");
    }
  }
  for (uint64_t i = 0; i < frame.positions.size(); ++i) {
    if (!std::isfinite(frame.positions[i])) {
      throw render::Error(what + "particle " + std::to_string(i / 3) + " has a non-finite position");
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<uint16_t> lod = io::lod_values(frame.ids, n);
  std::vector<std::vector<float>> zeros;  // attributes the host left out: zero
  io::FrameInput input{frame.positions, lod, {}, frame.time};
  for (size_t a = 0; a < header_.attributes.size(); ++a) {
    if (a < frame.attributes.size()) {
      input.attributes.push_back(frame.attributes[a]);
    } else {
      zeros.emplace_back(n, 0.0f);
      input.attributes.push_back(zeros.back());
    }
  }
  io::EncodedFrame encoded = io::encode_frame(input, header_, options_.encode);
  io::set_frame_number(encoded, uint32_t(pushed_), header_.attributes.size());
  encode_ms_ = ms_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  const uint64_t ticket = render::commit_record(renderer_, encoded.record, encoded.header, header_,
                                                options_.color_attribute, io::ErrorLocation{"live", pushed_, {}});
  decode_ms_ = ms_since(t1);
  if (writer_) writer_->append(std::move(encoded));
  ++pushed_;
  return ticket;
}

void LiveSource::finish() {
  if (writer_) writer_->finish();
  writer_.reset();
}

}  // namespace sluice::stream
