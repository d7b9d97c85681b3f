# rhot_options: an interface target every rhot target links. It carries the language standard,
# warnings and (optionally) sanitizers, so no global flags are needed.
add_library(rhot_options INTERFACE)
add_library(rhot::options ALIAS rhot_options)
set_target_properties(rhot_options PROPERTIES EXPORT_NAME options)
target_compile_features(rhot_options INTERFACE cxx_std_23)
# rhot's own warnings are for rhot's own code: an application built on the installed package gets
# the language standard and, from a sanitized build, the sanitizers its libraries need.
target_compile_options(rhot_options INTERFACE
  $<BUILD_INTERFACE:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion -Wnon-virtual-dtor
  -Wold-style-cast -Wdouble-promotion
  # Clang's null-dereference warning follows the code as written; GCC 12's at -O2 follows the
  # optimiser's paths and flags a vector written after it was sized (C3d.cpp, HandCalibration.cpp),
  # which broke the release preset's build.
  $<$<CXX_COMPILER_ID:Clang>:-Wnull-dereference>
  # A target's own exceptions (the RHOT_WARNING_EXCEPTIONS property) come after the warnings they
  # turn off: a target's private options would come before this interface's and be overridden.
  $<TARGET_PROPERTY:RHOT_WARNING_EXCEPTIONS>
  $<$<BOOL:${RHOT_WERROR}>:-Werror>>)
if(RHOT_SANITIZE)
  # -O1, as AddressSanitizer's authors advise: the checks stay, the tests (which run the whole
  # pipeline for thousands of frames) run several times faster than at -O0. GCC 12's
  # maybe-uninitialized analysis is unreliable with sanitizers and optimisation together (it flags
  # libstdc++'s own std::regex and std::function); the debug and release builds keep the warning.
  # Programs whose own code is thin (RHOT_THIN_PROGRAM: the test programs, set by rhot_add_test,
  # and most command-line tools, tools/CMakeLists.txt) are compiled at -O0: their own code is
  # assertions, flags and set-up, while the libraries they call keep -O1. Measured with Clang 19,
  # the tools' compile steps took 225 s instead of 500 s (docs/PERFORMANCE.md, "Build and test
  # time"); the checks are the same at either level. So are the libraries whose code runs once a
  # program or a little each frame (RHOT_THIN_LIBRARY, rhot_add_library's THIN: loading scenes and
  # meshes, the frame loop's bookkeeping, the composition root, streaming out): at -O0 their units
  # take about half the CPU to compile. Not the renderer, the runtime or the simulated world: at
  # -O0 the demo's tests ran two to six times longer.
  # The optimisation level is the build tree's own choice: an application on the installed
  # package (tools/examples) gets the sanitizers its libraries need and picks its own level.
  target_compile_options(rhot_options INTERFACE
    $<BUILD_INTERFACE:$<IF:$<OR:$<BOOL:$<TARGET_PROPERTY:RHOT_THIN_PROGRAM>>,$<BOOL:$<TARGET_PROPERTY:RHOT_THIN_LIBRARY>>>,-O0,-O1>>
    -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
    $<BUILD_INTERFACE:$<$<CXX_COMPILER_ID:GNU>:-Wno-maybe-uninitialized>>)
  target_link_options(rhot_options INTERFACE -fsanitize=address,undefined)
  # Eigen's expression functions (EIGEN_STRONG_INLINE: plain `inline` on GCC and Clang) always
  # inlined in the -O1 libraries: with UBSan's checks in each of them they grow past the inliner's
  # threshold, and a 3-vector difference became a chain of calls (Eigen's out-of-line expression
  # code was 25 % of the whole test suite's CPU time, perf over `ctest`; with them inlined the
  # suite took 552 s of test time instead of 749 s, for 10 % more build). The thin programs keep
  # plain inline: their -O0 code is not where the time goes. So do libraries whose Eigen code is
  # compiled for its own sake and little run (RHOT_EIGEN_PLAIN_INLINE: tracking/core's
  # decompositions, tracking/filter's Kalman filter), where inlining only lengthens the build.
  # Measured with Clang only: GCC makes an always_inline function it cannot inline an error (which
  # is why Eigen does not use the attribute there), so GCC's sanitized builds keep plain inline.
  option(RHOT_EIGEN_ALWAYS_INLINE "Sanitized Clang builds: always inline Eigen's expression functions in the libraries" ON)
  if(RHOT_EIGEN_ALWAYS_INLINE AND CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    set(rhot_plain_inline $<OR:$<BOOL:$<TARGET_PROPERTY:RHOT_THIN_PROGRAM>>,$<BOOL:$<TARGET_PROPERTY:RHOT_THIN_LIBRARY>>,$<BOOL:$<TARGET_PROPERTY:RHOT_EIGEN_PLAIN_INLINE>>>)
    target_compile_definitions(rhot_options INTERFACE
      $<BUILD_INTERFACE:$<$<NOT:${rhot_plain_inline}>:EIGEN_STRONG_INLINE=inline\ __attribute__\(\(always_inline\)\)>>)
    unset(rhot_plain_inline)
  endif()
endif()

# Linking: LLVM's lld where there is one (tools/setup-deps.sh installs it), else binutils' gold.
# Both link the debug builds' large executables several times faster than the default ld.bfd
# (measured: engine_demo_test 4.8 s with bfd, 2.6 s with gold, 0.9 s with lld); there are some
# forty executables per build.
include(CheckLinkerFlag)
check_linker_flag(CXX "-fuse-ld=lld" RHOT_HAVE_LLD)
if(RHOT_HAVE_LLD)
  target_link_options(rhot_options INTERFACE $<BUILD_INTERFACE:-fuse-ld=lld>)
else()
  check_linker_flag(CXX "-fuse-ld=gold" RHOT_HAVE_GOLD)
  if(RHOT_HAVE_GOLD)
    target_link_options(rhot_options INTERFACE $<BUILD_INTERFACE:-fuse-ld=gold>)
  endif()
endif()
# A program records only the shared libraries it calls into: a test of the hand tracker linked 262
# (OpenCV's every module through the simulation's link interface, Ceres, Vulkan, ...) and 159 with
# --as-needed, and starts in 0.35 s instead of 0.54 s under the sanitizers. Each of the ~500 tests
# is a process of its own, so CI's test time falls by about a minute of CPU.
target_link_options(rhot_options INTERFACE $<BUILD_INTERFACE:-Wl,--as-needed>)
# --as-needed alone still left the hand tracker's test with 159 libraries and the geometry test
# with 260: a unity object is one archive member, pulled in whole for any one of its symbols (even a
# weak copy of std::string::reserve), and with it every library its other functions call (the
# video source's OpenCV capture: GStreamer and FFmpeg; the calibration's image files: GDAL). With a
# section per function and per global, lld's --gc-sections keeps only the code reached from the
# program's own, and records a library as needed only when live code calls it.
target_compile_options(rhot_options INTERFACE $<BUILD_INTERFACE:-ffunction-sections -fdata-sections>)
target_link_options(rhot_options INTERFACE $<BUILD_INTERFACE:-Wl,--gc-sections>)

include(GNUInstallDirs)
set(RHOT_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/rhot)   # include/rhot/engine/core/World.h
set(RHOT_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/rhot)  # rhotConfig.cmake
set(RHOT_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/rhot)        # assets/, shaders/
install(TARGETS rhot_options EXPORT rhotTargets)

# rhot_add_library(NAME [INTERFACE] [THIN] [SOURCES...] [PUBLIC_LIBS ...] [PRIVATE_LIBS ...])
# One library per folder; the include root is the repository root, so code includes
# "engine/core/World.h" and "tracking/core/Rigid3.h": a file's folder is its layer. INTERFACE: a
# folder of headers only. THIN: code that runs little (-O0 under the sanitizers, above). Every library is installed and exported as rhot::<layer>_<folder>
# (rhot_engine_core: rhot::engine_core), with the include root include/rhot.
function(rhot_add_library name)
  cmake_parse_arguments(ARG "INTERFACE;THIN" "" "SOURCES;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  string(REGEX REPLACE "^rhot_" "" export_name "${name}")
  if(ARG_INTERFACE)
    add_library(${name} INTERFACE)
    target_include_directories(${name} INTERFACE $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}> $<INSTALL_INTERFACE:${RHOT_INSTALL_INCLUDEDIR}>)
    target_link_libraries(${name} INTERFACE rhot::options ${ARG_PUBLIC_LIBS})
  else()
    add_library(${name} STATIC ${ARG_SOURCES})
    target_include_directories(${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}> $<INSTALL_INTERFACE:${RHOT_INSTALL_INCLUDEDIR}>)
    target_link_libraries(${name} PUBLIC rhot::options ${ARG_PUBLIC_LIBS} PRIVATE ${ARG_PRIVATE_LIBS})
  endif()
  set_target_properties(${name} PROPERTIES EXPORT_NAME ${export_name})
  if(ARG_THIN)
    set_target_properties(${name} PROPERTIES RHOT_THIN_LIBRARY ON)
  endif()
  install(TARGETS ${name} EXPORT rhotTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
endfunction()
