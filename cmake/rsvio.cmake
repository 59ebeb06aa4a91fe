# Helpers shared by every part of the build.

# Build fingerprint compiled into the framework and into every plugin; the host refuses a plugin
# whose fingerprint differs (C++ objects and Eigen types cross the boundary only between matching builds).
set(RSVIO_FINGERPRINT "${CMAKE_CXX_COMPILER_ID}-${CMAKE_CXX_COMPILER_VERSION}/eigen-${Eigen3_VERSION}/${CMAKE_BUILD_TYPE}")

# rsvio_add_plugin(<kind> <name> SOURCES a.cpp ... [LIBS ...])
# Builds plugins/<kind>/<name> as MODULE rsvio_<kind>_<name>.so into <bin>/plugins, hidden visibility,
# linked against the framework. The module must define RSVIO_PLUGIN_ENTRY (rsvio/plugin/plugin_api.h).
function(rsvio_add_plugin kind name)
  cmake_parse_arguments(P "" "" "SOURCES;LIBS" ${ARGN})
  set(tgt rsvio_${kind}_${name})
  add_library(${tgt} MODULE ${P_SOURCES})
  target_link_libraries(${tgt} PRIVATE rsvio_framework ${P_LIBS})
  set_target_properties(${tgt} PROPERTIES
    PREFIX ""
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON
    LIBRARY_OUTPUT_DIRECTORY ${RSVIO_PLUGIN_OUTPUT_DIR})
  target_compile_definitions(${tgt} PRIVATE RSVIO_PLUGIN_NAME="${kind}.${name}")
  set_property(GLOBAL APPEND PROPERTY RSVIO_PLUGIN_TARGETS ${tgt})
endfunction()

# Sanitizer build (scripts/sanitize.sh, its own build folder build-asan/): AddressSanitizer (with
# LeakSanitizer) and UndefinedBehaviorSanitizer on every target, framework, plugins, apps and tests.
# Any UB report aborts the program (-fno-sanitize-recover), so a test with a report fails.
option(RSVIO_SANITIZE "Build with -fsanitize=address,undefined (scripts/sanitize.sh)" OFF)
# -O1 (not -O2): GCC with both sanitizers spends over 15 minutes on one Eigen-heavy file at -O2.
# -fno-sanitize=vptr: the dynamic-type check is the costliest to compile and misfires across the
# dlopen'ed plugins built with hidden visibility.
# -fno-sanitize=alignment,null: with GCC 12 these two checks more than double the compile time of the
# Eigen-heavy files (measured on framework/src/backend/ba_linearize.cpp: 87 s with every check, 36 s
# without these two, 24 s at -O1 without any sanitizer), which is what fits the sanitizer pass into CI's
# budget. AddressSanitizer still stops a null dereference (SEGV on address 0x0, with its stack) and a
# misaligned SIMD access that faults; what is no longer reported is a misaligned access the CPU
# tolerates, and a null pointer formed into a reference without being read. Every other UBSan check
# (signed overflow, shifts, bounds, float-to-int overflow, bool and enum loads, divide by zero, pointer
# overflow, unreachable, missing return) stays on.
set(RSVIO_SANITIZE_UB_SKIP "vptr,alignment,null" CACHE STRING "UBSan checks left out of the sanitizer build")
if(RSVIO_SANITIZE)
  set(CMAKE_CXX_FLAGS_RELEASE "-O1 -DNDEBUG")
  set(RSVIO_SANITIZE_FLAGS -fsanitize=address,undefined -fno-sanitize=${RSVIO_SANITIZE_UB_SKIP} -fno-omit-frame-pointer
                           -fno-sanitize-recover=undefined -g1)
  add_compile_options(${RSVIO_SANITIZE_FLAGS})
  add_link_options(-fsanitize=address,undefined)
  add_compile_definitions(RSVIO_SANITIZE=1)
endif()
