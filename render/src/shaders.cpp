// The embedded SPIR-V (see shaders.h). The .inc files are glslc -mfmt=c
// output generated into the build tree.
#include "shaders.h"

namespace sluice::render {
namespace {
const uint32_t kCullChunks[] =
#include "cull_chunks.comp.inc"
    ;
const uint32_t kCullArgs[] =
#include "cull_args.comp.inc"
    ;
const uint32_t kCullParticles[] =
#include "cull_particles.comp.inc"
    ;
const uint32_t kSplat[] =
#include "splat.comp.inc"
    ;
const uint32_t kResolve[] =
#include "resolve.comp.inc"
    ;
const uint32_t kSphereVert[] =
#include "sphere.vert.inc"
    ;
const uint32_t kSphereDepthFrag[] =
#include "sphere_depth.frag.inc"
    ;
const uint32_t kSphereThicknessFrag[] =
#include "sphere_thickness.frag.inc"
    ;
const uint32_t kFilterDepth[] =
#include "filter_depth.comp.inc"
    ;
const uint32_t kFilterThickness[] =
#include "filter_thickness.comp.inc"
    ;
const uint32_t kComposite[] =
#include "composite.comp.inc"
    ;
const uint32_t kPresentVert[] =
#include "present.vert.inc"
    ;
const uint32_t kPresentFrag[] =
#include "present.frag.inc"
    ;
const uint32_t kBandBounds[] =
#include "band_bounds.comp.inc"
    ;
const uint32_t kBandGrid[] =
#include "band_grid.comp.inc"
    ;
const uint32_t kBandInsert[] =
#include "band_insert.comp.inc"
    ;
const uint32_t kBandVoxels[] =
#include "band_voxels.comp.inc"
    ;
const uint32_t kBandL1[] =
#include "band_l1.comp.inc"
    ;
const uint32_t kBandL2[] =
#include "band_l2.comp.inc"
    ;
const uint32_t kBandScatter[] =
#include "band_scatter.comp.inc"
    ;
const uint32_t kBandParticles[] =
#include "band_particles.comp.inc"
    ;
const uint32_t kBandBlobs[] =
#include "band_blobs.comp.inc"
    ;
const uint32_t kBandGather[] =
#include "band_gather.comp.inc"
    ;
const uint32_t kBandApply[] =
#include "band_apply.comp.inc"
    ;
const uint32_t kBandEllipsoids[] =
#include "band_ellipsoids.comp.inc"
    ;
const uint32_t kDecode[] =
#include "decode.comp.inc"
    ;
}  // namespace

vk::raii::Pipeline compute_pipeline(const vk::raii::Device& device, const vk::raii::PipelineLayout& layout, Shader s,
                                    bool ellipsoids) {
  const std::span<const uint32_t> code = spirv(s);
  const vk::raii::ShaderModule m(device, vk::ShaderModuleCreateInfo({}, code.size_bytes(), code.data()));
  const vk::Bool32 value = ellipsoids ? VK_TRUE : VK_FALSE;
  const vk::SpecializationMapEntry entry(0, 0, sizeof value);  // constant_id 0: common.glsl's kEllipsoids
  const vk::SpecializationInfo specialization(1, &entry, sizeof value, &value);
  const vk::ComputePipelineCreateInfo info(
      {}, vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eCompute, *m, "main", &specialization), *layout);
  return vk::raii::Pipeline(device, nullptr, info);
}

std::span<const uint32_t> spirv(Shader s) {
  switch (s) {
    case Shader::CullChunks: return kCullChunks;
    case Shader::CullArgs: return kCullArgs;
    case Shader::CullParticles: return kCullParticles;
    case Shader::Splat: return kSplat;
    case Shader::Resolve: return kResolve;
    case Shader::SphereVert: return kSphereVert;
    case Shader::SphereDepthFrag: return kSphereDepthFrag;
    case Shader::SphereThicknessFrag: return kSphereThicknessFrag;
    case Shader::FilterDepth: return kFilterDepth;
    case Shader::FilterThickness: return kFilterThickness;
    case Shader::Composite: return kComposite;
    case Shader::PresentVert: return kPresentVert;
    case Shader::PresentFrag: return kPresentFrag;
    case Shader::BandBounds: return kBandBounds;
    case Shader::BandGrid: return kBandGrid;
    case Shader::BandInsert: return kBandInsert;
    case Shader::BandVoxels: return kBandVoxels;
    case Shader::BandL1: return kBandL1;
    case Shader::BandL2: return kBandL2;
    case Shader::BandScatter: return kBandScatter;
    case Shader::BandParticles: return kBandParticles;
    case Shader::BandBlobs: return kBandBlobs;
    case Shader::BandGather: return kBandGather;
    case Shader::BandApply: return kBandApply;
    case Shader::BandEllipsoids: return kBandEllipsoids;
    case Shader::Decode: return kDecode;
  }
  return {};
}

}  // namespace sluice::render
