# A precompiled header for the thin command-line programs (Clang only; the tests have their own,
# tests/CMakeLists.txt). Their own code is compiled at -O0 under the sanitizers (RHOT_THIN_PROGRAM,
# cmake/RhotOptions.cmake), where parsing CLI11, nlohmann-json, spdlog, fmt, Eigen and OpenCV is most
# of a unit's time: rhot-plan's unit took 21.6 s of CPU without it and 12.3 s with it. The libraries
# (-O1) gain nothing: measured, their units took as long or longer with a precompiled header (Clang
# then generates code for the header's inline functions they use as before, and parsing is a small
# part of an optimised unit), so they have none (docs/PERFORMANCE.md, "Build time").
# Clang accepts a precompiled header whose macros are a superset or subset of a unit's as long as
# none differs; GCC invalidates it for any macro that touches its headers, so the GCC builds (the
# debug preset) parse the headers in each unit as before.
option(RHOT_PCH "Precompile the heavy third-party headers once for the command-line programs (Clang)" ON)
set(RHOT_USE_PCH OFF)
if(RHOT_PCH AND CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  set(RHOT_USE_PCH ON)
  add_library(rhot_thin_pch STATIC ${PROJECT_SOURCE_DIR}/cmake/RhotPch.cpp)
  set_target_properties(rhot_thin_pch PROPERTIES RHOT_THIN_PROGRAM ON)
  target_link_libraries(rhot_thin_pch PRIVATE rhot::options Eigen3::Eigen opencv_core fmt::fmt spdlog::spdlog nlohmann_json::nlohmann_json
    CLI11::CLI11)
  target_precompile_headers(rhot_thin_pch PRIVATE
    <algorithm> <array> <chrono> <cmath> <cstdint> <cstdio> <expected> <filesystem> <fstream> <functional> <limits> <map>
    <memory> <optional> <random> <span> <sstream> <string> <string_view> <unordered_map> <vector>
    <Eigen/Core> <Eigen/Geometry> <opencv2/core.hpp> <fmt/format.h> <spdlog/spdlog.h> <nlohmann/json.hpp> <CLI/CLI.hpp>)
endif()

# rhot_use_thin_pch(TARGET): a thin program's units start from the precompiled header. Its files
# still include what they use: the debug preset (GCC, no unity build, no precompiled header)
# compiles every file on its own.
function(rhot_use_thin_pch name)
  if(NOT RHOT_USE_PCH)
    return()
  endif()
  # libstdc++ silences its own deprecated get_temporary_buffer (std::stable_sort's buffer) with a
  # diagnostic pragma that Clang 19 does not carry through a precompiled header: every stable_sort
  # would be an error under -Werror. Deprecations are still errors in the GCC builds.
  target_compile_options(${name} PRIVATE -Wno-deprecated-declarations)
  target_precompile_headers(${name} REUSE_FROM rhot_thin_pch)
endfunction()
