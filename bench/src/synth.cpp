#include "sluice/bench/synth.h"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "sluice/import/frames.h"
#include "sluice/io/writer.h"

namespace sluice::bench {
namespace {

// splitmix64's finaliser: a cheap, well-mixed hash of a particle (and frame).
uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Uniform in [-0.5, 0.5).
float centred(uint64_t hash) { return float(hash >> 40) * (1.0f / 16777216.0f) - 0.5f; }

// Particles fill x fastest, then z, then y: a partial last layer is the top
// of the water, not a hole in its side. Twice as long as wide and high.
struct Block {
  uint64_t nx, ny, nz;
};

Block block_for(uint64_t n) {
  const auto side = std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(std::cbrt(double(n) / 2.0))));
  const uint64_t nx = 2 * side, nz = side;
  return {nx, std::max<uint64_t>(1, (n + nx * nz - 1) / (nx * nz)), nz};
}

class SyntheticSource final : public import::FrameSource {
 public:
  explicit SyntheticSource(SynthOptions o) : o_(std::move(o)), block_(block_for(o_.particles)) {
    info_.description = std::string("synthetic ") + (o_.motion == SynthMotion::Slosh ? "sloshing wave block" : "drifting lattice") +
                        ", " + std::to_string(o_.particles) + " particles";
    info_.id_array = "id";
    info_.arrays = {"id"};
    if (o_.speed_attribute) info_.arrays.push_back("speed");
  }

  uint64_t frame_count() const override { return o_.frames; }
  const import::SourceInfo& info() const override { return info_; }
  std::string frame_name(uint64_t i) const override { return "synthetic frame " + std::to_string(i); }

  io::ParticleFrame read(uint64_t frame) const override {
    const uint64_t n = o_.particles;
    io::ParticleFrame f;
    f.time = double(frame) / o_.frame_rate;
    f.time_given = true;
    f.positions.resize(3 * n);
    f.ids.resize(n);
    if (o_.speed_attribute) f.attributes.assign(1, std::vector<float>(n));

    const auto t = static_cast<float>(f.time);
    const float h = o_.spacing;
    const float height = float(block_.ny) * h;
    const float omega = 2.f * std::numbers::pi_v<float> / 2.4f;  // one slosh every 2.4 s
    const float amplitude = 0.2f * height, sway = 0.25f * amplitude;
    const float rise = std::sin(omega * t), lean = std::cos(omega * t);
    // Per column of the tank: the standing wave's shape.
    std::vector<float> wave(block_.nx), drift(block_.nx);
    for (uint64_t x = 0; x < block_.nx; ++x) {
      const float phase = std::numbers::pi_v<float> * (float(x) + 0.5f) / float(block_.nx);
      wave[x] = std::cos(phase);
      drift[x] = std::sin(phase);
    }

    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, n, 1 << 15), [&](const tbb::blocked_range<uint64_t>& r) {
      for (uint64_t p = r.begin(); p != r.end(); ++p) {
        const uint64_t xi = p % block_.nx, zi = (p / block_.nx) % block_.nz, yi = p / (block_.nx * block_.nz);
        // A jitter the particle keeps, and a little that changes every frame
        // (solver noise): real data is never a perfect lattice.
        const uint64_t own = mix(p ^ (uint64_t(o_.seed) << 40));
        const uint64_t now = mix(own + frame);
        const float x0 = (float(xi) + 0.5f + 0.3f * centred(own)) * h + 0.05f * h * centred(now);
        const float y0 = (float(yi) + 0.5f + 0.3f * centred(mix(own))) * h + 0.05f * h * centred(mix(now));
        const float z0 = (float(zi) + 0.5f + 0.3f * centred(mix(own + 1))) * h + 0.05f * h * centred(mix(now + 1));
        float x = x0, y = y0, z = z0, speed = 0;
        if (o_.motion == SynthMotion::Slosh) {
          const float depth = y0 / height;  // 0 at the floor, 1 at the rest surface
          y = y0 + depth * amplitude * wave[xi] * rise;
          x = x0 + depth * sway * drift[xi] * lean;
          const float vy = depth * amplitude * wave[xi] * omega * lean;
          const float vx = -depth * sway * drift[xi] * omega * rise;
          speed = std::sqrt(vx * vx + vy * vy);
        } else {
          x = x0 + 0.3f * t;
          y = y0 + 0.05f * std::sin(t + 20.f * z0);
          speed = 0.3f;
        }
        f.positions[3 * p] = x;
        f.positions[3 * p + 1] = y;
        f.positions[3 * p + 2] = z;
        f.ids[p] = p;
        if (o_.speed_attribute) f.attributes[0][p] = speed;
      }
    });
    return f;
  }

 private:
  SynthOptions o_;
  Block block_;
  import::SourceInfo info_;
};

}  // namespace

std::unique_ptr<import::FrameSource> synthetic_source(const SynthOptions& options) {
  return std::make_unique<SyntheticSource>(options);
}

SynthResult write_synthetic(const SynthOptions& o, const std::function<void(uint64_t, uint64_t)>& on_frame) {
  if (o.output.empty()) throw io::Error({}, "no output file given");
  if (o.particles == 0 || o.frames == 0) throw io::Error({o.output}, "nothing to write: particles and frames must be > 0");
  const auto source = synthetic_source(o);
  io::FileHeader header;
  header.position_coding = o.lossless ? io::PositionCoding::Float32 : io::PositionCoding::Quantized16;
  header.lod_source = io::LodSource::IdHash;
  header.lod_id_array = "id";
  header.particle_spacing = o.spacing;
  header.particle_radius = o.spacing / 2;
  header.precision_bits = o.lossless ? 0 : o.precision_bits;
  io::set_format_version(header, o.format_major);
  header.frame_rate = o.frame_rate;
  header.time_source = io::TimeSource::Step;
  header.up = io::UpAxis::PosY;  // the block's height runs along y
  header.up_evidence = io::UpEvidence::Given;
  if (o.speed_attribute) header.attributes.push_back({"speed"});
  header.source = "sluice synth: " + source->info().description;

  const std::string partial = o.output + ".partial";
  io::ContainerWriter writer(partial, header);
  io::EncodeOptions encode;
  encode.chunk_particles = o.chunk_particles;
  encode.zstd_level = o.zstd_level;
  encode.planes = o.planes;
  encode.lod_tiers = o.lod_tiers;
  encode.layers = o.layers;
  const size_t jobs = o.jobs > 0 ? size_t(o.jobs) : size_t(tbb::info::default_concurrency());
  const import::FramesResult r = import::convert_frames(*source, std::nullopt, writer, import::FramesSettings{.encode = encode, .max_in_flight = jobs + 1},
                                                 [&](const import::FrameConverted& p) {
                                                   if (on_frame) on_frame(p.frame + 1, writer.bytes_written());
                                                 });
  writer.finish();
  std::filesystem::rename(partial, o.output);
  return {r.frames, r.particles, std::filesystem::file_size(o.output)};
}

}  // namespace sluice::bench
