// Timed copies into device-local memory: from mapped staging, and from host
// memory imported through VK_EXT_external_memory_host.
#include "sluice/render/transfer_bound.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstring>
#include <vector>

#include "vk_common.h"

namespace sluice::render {
namespace {

// Copies `bytes` from `source` to `target` on the transfer queue, `repeats`
// times after a warm-up; GB/s of the median (submission to fence).
double timed_copy_gbps(Context::Impl& ctx, vk::Buffer source, vk::Buffer target, uint64_t bytes, int repeats) {
  const vk::raii::CommandPool pool(ctx.device, vk::CommandPoolCreateInfo({}, ctx.transfer_family));
  vk::raii::CommandBuffers cmds(ctx.device, vk::CommandBufferAllocateInfo(*pool, vk::CommandBufferLevel::ePrimary, 1));
  const vk::CommandBuffer cmd = *cmds[0];
  cmd.begin(vk::CommandBufferBeginInfo());
  cmd.copyBuffer(source, target, vk::BufferCopy(0, 0, bytes));
  cmd.end();
  std::vector<double> seconds;
  for (int k = 0; k <= std::max(repeats, 1); ++k) {
    const vk::raii::Fence fence(ctx.device, vk::FenceCreateInfo());
    const vk::CommandBufferSubmitInfo cb(cmd);
    const auto t0 = std::chrono::steady_clock::now();
    ctx.transfer_queue.submit2(vk::SubmitInfo2({}, {}, cb), *fence);
    while (ctx.device.waitForFences(*fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
    }
    if (k > 0) seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(seconds.begin(), seconds.end());
  return double(bytes) / seconds[seconds.size() / 2] / 1e9;
}

}  // namespace

double host_to_device_gbps(Context& context, uint64_t bytes, int repeats) {
  Context::Impl& ctx = context_impl(context);
  const Buffer staging = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
  const Buffer device = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::DeviceLocal);
  std::memset(staging.mapped, 1, bytes);  // pages touched before timing
  return timed_copy_gbps(ctx, *staging.buffer, *device.buffer, bytes, repeats);
}

uint64_t import_alignment(Context& context) {
  Context::Impl& ctx = context_impl(context);
  if (!ctx.external_memory_host) return 0;
  return ctx.physical
      .getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceExternalMemoryHostPropertiesEXT>()
      .get<vk::PhysicalDeviceExternalMemoryHostPropertiesEXT>()
      .minImportedHostPointerAlignment;
}

ImportedCopy imported_host_copy_gbps(Context& context, const void* host, uint64_t bytes, int repeats) {
  Context::Impl& ctx = context_impl(context);
  ImportedCopy out;
  const uint64_t alignment = import_alignment(context);
  if (alignment == 0) {
    out.refusal = "the device has no VK_EXT_external_memory_host";
    return out;
  }
  if (bytes == 0 || reinterpret_cast<uintptr_t>(host) % alignment != 0 || bytes % alignment != 0) {
    out.refusal = "pointer or size not a multiple of " + std::to_string(alignment) + " bytes";
    return out;
  }
  constexpr auto kHandle = vk::ExternalMemoryHandleTypeFlagBits::eHostAllocationEXT;
  try {
    const vk::MemoryHostPointerPropertiesEXT pointer = ctx.device.getMemoryHostPointerPropertiesEXT(kHandle, host);
    const vk::ExternalMemoryBufferCreateInfo external(kHandle);
    vk::BufferCreateInfo info({}, bytes, vk::BufferUsageFlagBits::eTransferSrc, vk::SharingMode::eExclusive);
    info.pNext = &external;
    vk::raii::Buffer source(ctx.device, info);
    const uint32_t types = source.getMemoryRequirements().memoryTypeBits & pointer.memoryTypeBits;
    if (types == 0) {
      out.refusal = "no memory type both the buffer and the imported pointer allow";
      return out;
    }
    const vk::ImportMemoryHostPointerInfoEXT import(kHandle, const_cast<void*>(host));
    vk::MemoryAllocateInfo allocate(bytes, uint32_t(std::countr_zero(types)));
    allocate.pNext = &import;
    vk::raii::DeviceMemory memory(ctx.device, allocate);
    source.bindMemory(*memory, 0);
    const Buffer device = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::DeviceLocal);
    out.gbps = timed_copy_gbps(ctx, *source, *device.buffer, bytes, repeats);
    out.imported = true;
  } catch (const vk::SystemError& e) {
    out.refusal = e.what();
  }
  return out;
}

}  // namespace sluice::render
