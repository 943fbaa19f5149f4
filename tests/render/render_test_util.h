// Shared by the render tests: one Vulkan context per test binary, with the
// validation layer on; every test ends by checking that it caused no
// validation error (skipped, with a note, where the layer is not installed).
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "sluice/render/context.h"

namespace sluice::render::testing {

inline Context& context() {
  static std::unique_ptr<Context> ctx = [] {
    ContextOptions o;
    o.validation = true;
    o.quiet_validation = true;
    auto c = std::make_unique<Context>(o);
    std::fprintf(stderr, "render tests on %s (%s), validation %s\n", c->device().name.c_str(), c->device().type.c_str(),
                 c->validation_active() ? "on" : "NOT AVAILABLE (VK_LAYER_KHRONOS_validation missing)");
    return c;
  }();
  return *ctx;
}

// Checks that no validation error happened since construction.
class ValidationGuard {
 public:
  ValidationGuard() : before_(context().validation_errors()) {}
  ~ValidationGuard() {
    Context& c = context();
    if (!c.validation_active()) return;
    const uint64_t errors = c.validation_errors() - before_;
    EXPECT_EQ(errors, 0u) << "Vulkan validation errors; first messages:\n" << [&] {
      std::string all;
      for (const std::string& m : c.validation_messages()) all += m + "\n";
      return all;
    }();
  }

 private:
  uint64_t before_;
};

}  // namespace sluice::render::testing
