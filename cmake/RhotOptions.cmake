# rhot_options: an interface target every rhot target links. It carries the language standard,
# warnings and (optionally) sanitizers, so no global flags are needed.
add_library(rhot_options INTERFACE)
add_library(rhot::options ALIAS rhot_options)
target_compile_features(rhot_options INTERFACE cxx_std_23)
target_compile_options(rhot_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion -Wnon-virtual-dtor
  -Wold-style-cast -Wnull-dereference -Wdouble-promotion
  $<$<BOOL:${RHOT_WERROR}>:-Werror>)
if(RHOT_SANITIZE)
  # -O1, as AddressSanitizer's authors advise: the checks stay, the tests (which run the whole
  # pipeline for thousands of frames) run several times faster than at -O0. GCC 12's
  # maybe-uninitialized analysis is unreliable with sanitizers and optimisation together (it flags
  # libstdc++'s own std::regex and std::function); the debug and release builds keep the warning.
  target_compile_options(rhot_options INTERFACE
    -O1 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined -Wno-maybe-uninitialized)
  target_link_options(rhot_options INTERFACE -fsanitize=address,undefined)
endif()

# rhot_add_library(NAME SOURCES... [PUBLIC_LIBS ...] [PRIVATE_LIBS ...])
# One library per layer; the include root is the repository root, so code includes
# "engine/core/World.h" and "tracking/core/Pose.h": a file's folder is its layer.
function(rhot_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC rhot::options ${ARG_PUBLIC_LIBS} PRIVATE ${ARG_PRIVATE_LIBS})
endfunction()
