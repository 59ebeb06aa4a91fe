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
# dlopen'ed plugins built with hidden visibility; every other UBSan check stays on.
if(RSVIO_SANITIZE)
  set(CMAKE_CXX_FLAGS_RELEASE "-O1 -DNDEBUG")
  set(RSVIO_SANITIZE_FLAGS -fsanitize=address,undefined -fno-sanitize=vptr -fno-omit-frame-pointer
                           -fno-sanitize-recover=undefined -g1)
  add_compile_options(${RSVIO_SANITIZE_FLAGS})
  add_link_options(-fsanitize=address,undefined)
  add_compile_definitions(RSVIO_SANITIZE=1)
endif()
