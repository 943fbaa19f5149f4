// Internal: OpenXR with its Vulkan binding, and result checking.
#pragma once

#include <vulkan/vulkan.h>

#define XR_USE_GRAPHICS_API_VULKAN 1
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <string>

namespace sluice::xr {

// Throws std::runtime_error "`what`: XR_ERROR_... " when `result` failed.
void check(XrResult result, XrInstance instance, const char* what);
std::string result_name(XrResult result, XrInstance instance);

// An extension function, looked up once per instance.
template <class F>
F instance_function(XrInstance instance, const char* name) {
  PFN_xrVoidFunction f = nullptr;
  check(xrGetInstanceProcAddr(instance, name, &f), instance, name);
  return reinterpret_cast<F>(f);
}

}  // namespace sluice::xr
