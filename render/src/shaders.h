// Internal: the SPIR-V of every shader, compiled by glslc at build time and
// embedded in the library (no files to find at run time).
#pragma once

#include <cstdint>
#include <span>

#include "vk_common.h"

namespace sluice::render {

enum class Shader {
  CullChunks,
  CullArgs,
  CullParticles,
  Splat,
  Resolve,
  SphereVert,
  SphereDepthFrag,
  SphereThicknessFrag,
  FilterDepth,
  FilterThickness,
  Composite,
  PresentVert,
  PresentFrag,
  BandBounds,
  BandGrid,
  BandInsert,
  BandVoxels,
  BandL1,
  BandL2,
  BandScatter,
  BandParticles,
  BandBlobs,
  BandGather,
  BandApply,
  BandEllipsoids,
  Decode,
};

std::span<const uint32_t> spirv(Shader s);

// A compute pipeline of shader `s` ("main") with `layout`.
// `ellipsoids`: common.glsl's kEllipsoids (specialization constant 0),
// which shaders that draw particles read to leave the ellipsoids' code out
// of the sphere pipelines.
vk::raii::Pipeline compute_pipeline(const vk::raii::Device& device, const vk::raii::PipelineLayout& layout, Shader s,
                                    bool ellipsoids = false);

}  // namespace sluice::render
