# Vulkan-Hpp in a namespace of sluice's own (sluice_vk; sources alias it as
# vk). Vulkan-Hpp's classes change layout with NDEBUG (DispatchLoaderBase
# gains members in debug builds), and its functions are inline: a host built
# in Debug that includes vulkan_raii.hpp and links sluice's Release static
# libraries would otherwise get one symbol with two layouts, and the linker
# keeps one of them (docs/embedding.md, "Vulkan-Hpp and the host's build").
# Sluice's public headers use Vulkan's C types only.
function(sluice_own_vulkan_hpp target)
  target_compile_definitions(${target} PRIVATE VULKAN_HPP_NAMESPACE=sluice_vk)
endfunction()
