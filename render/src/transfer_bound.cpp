// Timed copies from mapped staging into device-local memory.
#include "sluice/render/transfer_bound.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <vector>

#include "vk_common.h"

namespace sluice::render {

double host_to_device_gbps(Context& context, uint64_t bytes, int repeats) {
  Context::Impl& ctx = context_impl(context);
  const Buffer staging = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
  const Buffer device = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::DeviceLocal);
  std::memset(staging.mapped, 1, bytes);  // pages touched before timing
  const vk::raii::CommandPool pool(ctx.device, vk::CommandPoolCreateInfo({}, ctx.transfer_family));
  vk::raii::CommandBuffers cmds(ctx.device, vk::CommandBufferAllocateInfo(*pool, vk::CommandBufferLevel::ePrimary, 1));
  const vk::CommandBuffer cmd = *cmds[0];
  cmd.begin(vk::CommandBufferBeginInfo());
  cmd.copyBuffer(*staging.buffer, *device.buffer, vk::BufferCopy(0, 0, bytes));
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

}  // namespace sluice::render
