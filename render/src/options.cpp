// Option names (see options.h).
#include "sluice/render/options.h"

#include "sluice/render/options.h"

#include "sluice/io/up_axis.h"
#include "sluice/error.h"

#include <array>
#include <cctype>
#include <stdexcept>

namespace sluice::render {
namespace {

struct Name {
  const char* vtk;
  const char* short_name;
};
constexpr std::array<Name, 9> kDisplay{{
    {"UnfilteredOpaqueSurface", "opaque-unfiltered"},
    {"FilteredOpaqueSurface", "opaque"},
    {"UnfilteredSurfaceNormal", "normals-unfiltered"},
    {"FilteredSurfaceNormal", "normals"},
    {"UnfilteredDepth", "depth-unfiltered"},
    {"FilteredDepth", "depth"},
    {"ThicknessBuffer", "thickness-unfiltered"},
    {"FilteredThickness", "thickness"},
    {"TransparentFluidVolume", "transparent"},
}};

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

const char* to_string(DisplayMode m) { return kDisplay[size_t(m)].short_name; }
const char* to_string(SurfaceFilterMethod m) { return m == SurfaceFilterMethod::NarrowRange ? "narrow-range" : "bilateral"; }
const char* to_string(LodMode m) {
  return m == LodMode::Off ? "off" : m == LodMode::Clod ? "clod" : "density";
}
const char* to_string(Colormap m) {
  switch (m) {
    case Colormap::Viridis: return "viridis";
    case Colormap::Coolwarm: return "coolwarm";
    case Colormap::Turbo: return "turbo";
    case Colormap::Blues: return "blues";
  }
  return "viridis";
}

std::vector<std::string> display_mode_names() {
  std::vector<std::string> out;
  for (const Name& n : kDisplay) out.push_back(n.short_name);
  return out;
}

DisplayMode parse_display_mode(const std::string& s) {
  const std::string l = lower(s);
  for (size_t i = 0; i < kDisplay.size(); ++i) {
    if (l == kDisplay[i].short_name || l == lower(kDisplay[i].vtk)) return DisplayMode(i);
  }
  std::string choices;
  for (const Name& n : kDisplay) choices += std::string(choices.empty() ? "" : ", ") + n.short_name;
  throw Error("unknown display mode '" + s + "' (" + choices + ", or the VTK names)");
}

SurfaceFilterMethod parse_filter_method(const std::string& s) {
  const std::string l = lower(s);
  if (l == "narrow-range" || l == "narrowrange" || l == "nrf") return SurfaceFilterMethod::NarrowRange;
  if (l == "bilateral" || l == "bilateralgaussian" || l == "bilateral-gaussian") return SurfaceFilterMethod::BilateralGaussian;
  throw Error("unknown filter '" + s + "' (narrow-range, bilateral)");
}

void apply_particles(const std::string& name, RendererOptions& options) {
  if (name != "auto" && name != "spheres" && name != "ellipsoids") {
    throw Error("unknown particle look '" + name + "' (auto, spheres, ellipsoids)");
  }
  options.anisotropic = name != "spheres";
  options.anisotropic_limit = name == "auto" ? kAutoAnisotropicLimit : 0;
}

LodMode parse_lod_mode(const std::string& s) {
  const std::string l = lower(s);
  if (l == "off" || l == "none") return LodMode::Off;
  if (l == "clod" || l == "on") return LodMode::Clod;
  if (l == "density" || l == "density-preserving") return LodMode::DensityPreserving;
  throw Error("unknown LOD mode '" + s + "' (off, clod, density)");
}

Colormap parse_colormap(const std::string& s) {
  const std::string l = lower(s);
  for (Colormap c : {Colormap::Viridis, Colormap::Coolwarm, Colormap::Turbo, Colormap::Blues}) {
    if (l == to_string(c)) return c;
  }
  throw Error("unknown colormap '" + s + "' (viridis, coolwarm, turbo, blues)");
}

const char* to_string(Splatting m) {
  return m == Splatting::Compute ? "compute" : m == Splatting::Raster ? "raster" : "auto";
}

Splatting parse_splatting(const std::string& s) {
  const std::string l = lower(s);
  if (l == "auto") return Splatting::Auto;
  if (l == "compute") return Splatting::Compute;
  if (l == "raster" || l == "points") return Splatting::Raster;
  throw Error("unknown splatting '" + s + "' (auto, compute, raster)");
}

Vec3 parse_up(const std::string& s) {
  const std::optional<io::UpAxis> up = io::parse_up_axis(s);
  if (!up) throw Error("unknown axis '" + s + "' (x, y, z, -x, -y, -z)");
  const std::array<float, 3> v = io::up_vector(*up);
  return {v[0], v[1], v[2]};
}

}  // namespace sluice::render
