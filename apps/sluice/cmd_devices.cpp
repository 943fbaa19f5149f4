// `sluice devices`: the Vulkan devices this machine offers and what sluice
// thinks of each (the names and indices --device takes).
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "human.h"
#include "json_text.h"
#include "sluice/render/context.h"

namespace sluice::app {
namespace {

void print_text(const std::vector<render::DeviceInfo>& devices) {
  if (devices.empty()) {
    std::printf("no Vulkan device found (install a GPU driver, or mesa-vulkan-drivers for the CPU's lavapipe)\n");
    return;
  }
  for (const render::DeviceInfo& d : devices) {
    std::printf("%u: %s (%s, Vulkan %s, %s)\n", d.index, d.name.c_str(), d.type.c_str(), render::format_api_version(d.api_version).c_str(),
                d.driver.c_str());
    std::printf("   %s of device memory; splats up to %.0f pixels; %s\n", human_bytes(double(d.device_local_bytes)).c_str(),
                double(d.max_point_size), d.usable ? "sluice runs on it" : ("cannot run sluice: " + d.why_not).c_str());
  }
  std::printf("Choose one with --device INDEX or part of its name (default: the first discrete GPU, then integrated, "
              "then any).\n");
}

void print_json(const std::vector<render::DeviceInfo>& devices) {
  std::printf("[");
  for (size_t i = 0; i < devices.size(); ++i) {
    const render::DeviceInfo& d = devices[i];
    std::printf("%s\n  {\"index\": %u, \"name\": %s, \"type\": %s, \"driver\": %s, \"api_version\": %s, "
                "\"device_local_bytes\": %llu, \"max_point_size\": %s, \"usable\": %s, \"why_not\": %s}",
                i ? "," : "", d.index, json_string(d.name).c_str(), json_string(d.type).c_str(),
                json_string(d.driver).c_str(), json_string(render::format_api_version(d.api_version)).c_str(),
                (unsigned long long)d.device_local_bytes, json_number(d.max_point_size).c_str(), d.usable ? "true" : "false",
                json_string(d.why_not).c_str());
  }
  std::printf("\n]\n");
}

}  // namespace

void add_devices(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("devices", "List the Vulkan devices and whether sluice can run on each");
  cmd->footer("The index or part of the name is what --device takes in play, render, xr and bench.\n"
              "Example: sluice devices && sluice render run.sluice --device 1");
  cmd->add_flag("--json", *json, "Print JSON for scripts");
  cmd->callback([json] {
    const std::vector<render::DeviceInfo> devices = render::Context::list_devices();
    if (*json) print_json(devices);
    else print_text(devices);
  });
}

}  // namespace sluice::app
