#pragma once
// The OpenXR runtime the headset tests run against: the one XR_RUNTIME_JSON names, else the
// headless Monado (null compositor, simulated headset) in ../shared/openxr beside the source tree.
// Where there is neither, the tests skip with one line, except in CI (CI=true), where they must
// run and fail instead.

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include <gtest/gtest.h>

namespace rhot::test {

// The runtime's manifest, or nullopt.
inline std::optional<std::string> xr_test_runtime() {
  if (const char* json = std::getenv("XR_RUNTIME_JSON"); json != nullptr && *json != '\0') return std::string(json);
  const std::filesystem::path shared =
      std::filesystem::path(RHOT_SOURCE_DIR) / ".." / "shared" / "openxr" / "monado" / "openxr_monado.json";
  std::error_code ec;
  if (std::filesystem::is_regular_file(shared, ec)) return std::filesystem::weakly_canonical(shared, ec).string();
  return std::nullopt;
}

// What the runtime needs in its environment: Monado's simulated headset reports its tracking as
// valid (SIMULATED_ENABLE), its logs kept to warnings. Settings already made are kept.
inline std::string xr_test_environment(const std::string& runtime_json) {
  return "XR_RUNTIME_JSON=" + runtime_json + " SIMULATED_ENABLE=1 XRT_LOG=warn PROBER_LOG=warn XRT_COMPOSITOR_LOG=warn OXR_VULKAN_LOG=warn";
}

inline void set_xr_test_environment(const std::string& runtime_json) {
  setenv("XR_RUNTIME_JSON", runtime_json.c_str(), 1);
  for (const char* name : {"SIMULATED_ENABLE=1", "XRT_LOG=warn", "PROBER_LOG=warn", "XRT_COMPOSITOR_LOG=warn", "OXR_VULKAN_LOG=warn"}) {
    const std::string kv(name);
    const auto eq = kv.find('=');
    setenv(kv.substr(0, eq).c_str(), kv.substr(eq + 1).c_str(), 0);
  }
}

inline bool in_ci() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::string(ci) == "true";
}

}  // namespace rhot::test

// In a test body: `runtime` becomes the runtime's manifest, or the test skips (fails in CI).
#define RHOT_REQUIRE_XR_RUNTIME(runtime)                                                                                 \
  const std::optional<std::string> runtime##_found = ::rhot::test::xr_test_runtime();                                    \
  if (!runtime##_found) {                                                                                                \
    if (::rhot::test::in_ci())                                                                                           \
      FAIL() << "CI=true: the OpenXR tests must run, but there is no runtime (set XR_RUNTIME_JSON "                      \
                "or put ../shared/openxr beside the source tree)";                                                       \
    GTEST_SKIP() << "no OpenXR runtime: set XR_RUNTIME_JSON (or put ../shared/openxr beside the source tree) to run it"; \
  }                                                                                                                      \
  const std::string runtime = *runtime##_found
