// Timed copies into device-local memory: from mapped staging, and from host
// memory imported through VK_EXT_external_memory_host.
#include "sluice/render/transfer_bound.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <vector>

#include "vk_common.h"

namespace sluice::render {
namespace {

// Copies of `bytes` from `source` into device-local memory on the transfer
// queue, `in_flight` of them queued at a time (each into its own target),
// kept queued for at least `seconds` after one warm-up round; GB/s over the
// timed stretch, from the first submission to the last fence.
double sustained_copy_gbps(detail::ContextImpl& ctx, vk::Buffer source, uint64_t bytes, int in_flight, double seconds) {
  in_flight = std::max(in_flight, 1);
  const vk::raii::CommandPool pool(ctx.device, vk::CommandPoolCreateInfo({}, ctx.transfer_family));
  const vk::raii::CommandBuffers cmds(
      ctx.device, vk::CommandBufferAllocateInfo(*pool, vk::CommandBufferLevel::ePrimary, uint32_t(in_flight)));
  std::vector<Buffer> targets;
  std::vector<vk::raii::Fence> fences;
  for (int k = 0; k < in_flight; ++k) {
    targets.push_back(create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::DeviceLocal));
    fences.emplace_back(ctx.device, vk::FenceCreateInfo());
    const vk::CommandBuffer cmd = *cmds[k];
    cmd.begin(vk::CommandBufferBeginInfo());
    cmd.copyBuffer(source, *targets.back().buffer, vk::BufferCopy(0, 0, bytes));
    cmd.end();
  }
  const auto submit = [&](int k) {
    const vk::CommandBufferSubmitInfo cb(*cmds[k]);
    ctx.submit(ctx.transfer_queue, vk::SubmitInfo2({}, {}, cb), *fences[k]);
  };
  const auto wait = [&](int k) {
    ctx.wait(*fences[k]);
    ctx.device.resetFences(*fences[k]);
  };
  for (int k = 0; k < in_flight; ++k) submit(k);  // warm-up: first touches, clocks up
  for (int k = 0; k < in_flight; ++k) wait(k);
  const auto t0 = std::chrono::steady_clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  for (int k = 0; k < in_flight; ++k) submit(k);
  uint64_t copies = 0;
  for (int k = 0;; k = (k + 1) % in_flight) {
    wait(k);
    ++copies;
    // At least two rounds, so a single copy's start-up does not dominate.
    if (elapsed() >= seconds && copies >= uint64_t(2 * in_flight)) break;
    submit(k);
  }
  const double gbps = double(copies) * double(bytes) / elapsed() / 1e9;
  ctx.wait_idle(ctx.transfer_queue);  // the copies still queued, before their targets go
  return gbps;
}

}  // namespace

double host_to_device_gbps(Context& context, uint64_t bytes, const CopyShape& shape) {
  detail::ContextImpl& ctx = context_impl(context);
  const MemoryKind kind = shape.staging == StagingMemory::Cached ? MemoryKind::UploadRead : MemoryKind::Upload;
  const Buffer staging = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferSrc, kind);
  std::memset(staging.mapped, 1, bytes);  // pages touched before timing
  return sustained_copy_gbps(ctx, *staging.buffer, bytes, shape.in_flight, shape.seconds);
}

uint64_t import_alignment(Context& context) { return host_import_alignment(context_impl(context)); }

ImportedCopy imported_host_copy_gbps(Context& context, const void* host, uint64_t bytes, const CopyShape& shape) {
  detail::ContextImpl& ctx = context_impl(context);
  ImportedCopy out;
  const uint64_t alignment = host_import_alignment(ctx);
  if (alignment == 0) {
    out.refusal = "the device has no VK_EXT_external_memory_host";
    return out;
  }
  if (bytes == 0 || reinterpret_cast<uintptr_t>(host) % alignment != 0 || bytes % alignment != 0) {
    out.refusal = "pointer or size not a multiple of " + std::to_string(alignment) + " bytes";
    return out;
  }
  try {
    // Imported read-only in effect: the copy only reads it.
    const Buffer source = import_host_buffer(ctx, const_cast<void*>(host), bytes, vk::BufferUsageFlagBits::eTransferSrc);
    if (!source.mapped) {
      out.refusal = "no memory type both the buffer and the imported pointer allow";
      return out;
    }
    out.gbps = sustained_copy_gbps(ctx, *source.buffer, bytes, shape.in_flight, shape.seconds);
    out.imported = true;
  } catch (const vk::SystemError& e) {
    out.refusal = e.what();
  }
  return out;
}

}  // namespace sluice::render
