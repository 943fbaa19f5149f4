// sluice/render/options.h: everything that changes how a frame looks or how
// much of it is drawn. Plain values, cheap to copy; change them between frames
// freely (nothing is rebuilt except where noted).
//
// Names follow vtkOpenGLFluidMapper's where they mean the same thing (table
// 2.1 of the Tsinghua thesis on the mapper; docs/render.md cites it), in snake_case:
// ParticleRadius -> particle_radius, DisplayMode -> display_mode, ...
// Units: world units for lengths, pixels where the name says so.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sluice/render/frame.h"
#include "sluice/render/math.h"

namespace sluice::render {

// vtkOpenGLFluidMapper::FluidDisplayMode, plus nothing else.
enum class DisplayMode : uint32_t {
  UnfilteredOpaqueSurface = 0,
  FilteredOpaqueSurface = 1,
  UnfilteredSurfaceNormal = 2,
  FilteredSurfaceNormal = 3,
  UnfilteredDepth = 4,
  FilteredDepth = 5,
  ThicknessBuffer = 6,
  FilteredThickness = 7,
  TransparentFluidVolume = 8,
};

// vtkOpenGLFluidMapper::FluidSurfaceFilterMethod.
enum class SurfaceFilterMethod : uint32_t {
  BilateralGaussian = 0,
  NarrowRange = 1,  // Truong & Yuksel 2018, with bias correction and dynamic range
};

// How sphere impostors reach the depth and thickness buffers. Both give the
// exact ray-sphere depth per pixel.
enum class Splatting : uint32_t {
  Compute = 0,  // compute shader with atomics: fast where raster units are few (H100: 10x), order-independent
  Raster = 1,   // point sprites through the graphics pipeline: faster on CPU implementations (lavapipe: 4x)
  Auto = 2,     // Raster on CPU devices, Compute on GPUs
};

enum class Colormap : uint32_t { Viridis = 0, Coolwarm = 1, Turbo = 2, Blues = 3 };

struct FluidOptions {
  // Radius of the rendered spheres; 0 takes the file's particle spacing (twice
  // the stored radius: spheres that overlap give a continuous surface).
  float particle_radius = 0.0f;
  DisplayMode display_mode = DisplayMode::TransparentFluidVolume;
  float refractive_index = 1.33f;
  // How far (in units of the fluid's thickness) refracted rays are bent.
  float refraction_scale = 1.0f;
  // Extra reflection of the environment on top of Fresnel, 0..1.
  float additional_reflection = 0.0f;
  // Colour the fluid by the attribute chosen below (vertex colours in VTK).
  bool scalar_visibility = false;
  // Colour absorbed exponentially with thickness (Beer-Lambert), and its scale
  // per world unit of thickness. 0: automatic, 6 / (diagonal of the data's
  // bounds), so a liquid looks like water whatever the units.
  Vec3 attenuation_color{0.6f, 0.15f, 0.06f};
  float attenuation_scale = 0.0f;
  // Surface colour of the opaque display modes.
  Vec3 opaque_color{0.0f, 0.4f, 0.8f};

  SurfaceFilterMethod surface_filter_method = SurfaceFilterMethod::NarrowRange;
  // Largest depth-filter kernel radius in pixels. The radius actually used at
  // a pixel comes from the particle radius, its depth and the fov (Truong &
  // Yuksel's sigma_i = H*sigma / (2 z tan(fov/2)), kernel = 3 sigma_i).
  int surface_filter_radius = 20;
  int surface_filter_iterations = 2;  // 1..3 for the narrow-range filter
  // Gaussian over the thickness and colour buffers, pixels of that buffer.
  int thickness_and_volume_color_filter_radius = 8;
  int thickness_and_volume_color_filter_iterations = 1;
  // Thickness (and colour) buffer at half the resolution in each axis.
  bool half_resolution_thickness = true;
  Splatting splatting = Splatting::Auto;

  // Colouring by attribute (when scalar_visibility).
  int color_attribute = 0;                // index into the file's attributes
  std::optional<float> color_min, color_max;  // default: the file's observed range
  Colormap colormap = Colormap::Viridis;

  // Scene around the fluid.
  Vec3 up{0, 0, 1};                 // world direction that points up (normalized here; a file's: SceneInfo::up)
  bool ground = true;               // a checkered plane under the fluid's bounds, across `up`
  Vec3 light_direction{0.4f, -0.3f, 1.0f};  // towards the sun; given with z up, turned to `up`
};

enum class LodMode : uint32_t {
  Off = 0,              // draw everything inside the frustum
  Clod = 1,             // thesis formula 3.1: drop particles at random, keep splat size
  DensityPreserving = 2,  // as Clod, and kept splats grow by (1/p)^(1/3) so the surface has no holes
};

enum class LodRandom : uint32_t {
  Stable = 0,        // the container's per-particle value (no flicker during playback)
  PositionHash = 1,  // thesis formula 3.2 on the world position (flickers when particles move)
};

// Continuous LOD, culling and the limits that protect the screen-space filter.
struct LodOptions {
  LodMode mode = LodMode::Off;
  // The user's threshold, 0..1: 1 keeps every particle inside the frustum,
  // lower keeps fewer (about `level` of them where a particle's importance is 1).
  float level = 1.0f;
  // Distance at which the importance of a particle at the screen centre is 1
  // (the thesis's CLOD constant, as a length). 0: the diagonal of the data's
  // bounds, so the default view keeps about `level` of the particles.
  float reference_distance = 0.0f;
  LodRandom random = LodRandom::Stable;
  // Near-camera culling (thesis 3.4): particles closer than this to the eye
  // are dropped. 0: only those crossing the near plane.
  float near_cull_distance = 0.0f;
  // Particles whose sphere would cover more than this many pixels across are
  // dropped too (thesis 3.4: they only spoil the filter). 0: the device's
  // largest point size.
  float max_splat_pixels = 0.0f;
  // Largest growth factor of a kept splat in DensityPreserving mode.
  float max_splat_scale = 4.0f;
  // Precision by distance (format 3.0 files): a record far enough away is
  // read without the low bits of its positions when that moves none of its
  // particles more than this many pixels on screen (runtime::coarse_enough).
  // 0: positions always read at full precision. Applies with or without LOD.
  float position_error_pixels = 0.1f;
};

// Names used on the command line and in camera/option strings.
const char* to_string(DisplayMode m);
const char* to_string(SurfaceFilterMethod m);
const char* to_string(LodMode m);
const char* to_string(Colormap m);
const char* to_string(Splatting m);
Splatting parse_splatting(const std::string& s);  // "auto" | "compute" | "raster"
// Accepts the VTK name ("TransparentFluidVolume") or the short one
// ("transparent", "opaque", "normals", "depth", "thickness", ...).
// Throws render::Error listing the choices.
DisplayMode parse_display_mode(const std::string& s);
SurfaceFilterMethod parse_filter_method(const std::string& s);  // "narrow-range" | "bilateral"
LodMode parse_lod_mode(const std::string& s);                   // "off" | "clod" | "density"
Colormap parse_colormap(const std::string& s);
std::vector<std::string> display_mode_names();  // short names, in enum order
// "x" | "y" | "z" | "-x" | "-y" | "-z" (and "+x" ...) -> that unit vector.
Vec3 parse_up(const std::string& s);

// The largest frame the apps' `--particles auto` (their default) draws as
// ellipsoids (RendererOptions::anisotropic_limit): their once-a-frame pass
// takes about 3 ms per million particles on an H100 (docs/render.md), so a
// new frame of this size costs one stereo frame's time at 90 Hz at most.
inline constexpr uint64_t kAutoAnisotropicLimit = 2'000'000;

struct RendererOptions {
  uint32_t frames_in_flight = 2;  // see the contract above; 1..8
  // Keep each view's eye normals and depth for read_surface() (render/internal: inspection.h; costs
  // 16 bytes per pixel per frame).
  bool debug_surfaces = false;
  // Frames that arrive without layers (files converted with --no-layers,
  // frames a host pushes live: every chunk io::Layer::All, or staged rows
  // with no blob chunk) are classified on the GPU when first drawn (the
  // narrow band of io/narrow_band.h, voxel 2h, h = the scene's particle
  // spacing, else twice its radius) and drawn from their surface and voxel
  // blobs, as a layered file's surface set is. Costs the classification once
  // per uploaded frame (a pass "classify" in FrameStats), a bit per particle,
  // and room for n/4 blobs after the particles; a frame with more blobs, or
  // whose grid is too large, is drawn whole.
  bool classify_unlayered = false;
  // Anisotropic particles (Yu & Turk 2013): each particle drawn as an
  // ellipsoid from the covariance of its neighbours within 2h (h = the
  // scene's particle spacing, else twice its radius), flat where the fluid
  // is flat, so a resting surface shades smooth instead of showing the
  // particles' lattice. Computed on the GPU when a frame is first drawn (a
  // pass "ellipsoids" in FrameStats, or part of "classify"), 12 bytes per
  // particle and the classifier's scratch; each radius at most 4 times
  // another, volume kept; a particle with fewer than 6 others near it stays
  // a sphere, as do blobs. Needs a known particle size; otherwise, and for
  // a frame of more than 2^28 particles, particles stay spheres.
  bool anisotropic = false;
  // With `anisotropic`: a frame of more particles than this is drawn as
  // spheres, so the once-a-frame pass stays short (0: no limit but 2^28).
  // The apps' `--particles auto` sets kAutoAnisotropicLimit.
  uint64_t anisotropic_limit = 0;
};

// The particle look by name, as `--particles` and the Python module take
// it, into `options`' anisotropic and anisotropic_limit: "spheres",
// "ellipsoids", or "auto" (ellipsoids up to kAutoAnisotropicLimit particles
// a frame). Throws render::Error listing the choices.
void apply_particles(const std::string& name, RendererOptions& options);

// Effective sphere radius for `options` in `scene`.
float effective_radius(const FluidOptions& options, const SceneInfo& scene);

}  // namespace sluice::render
