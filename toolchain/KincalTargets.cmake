# Compile options shared by every kincal target; one place to change them.

option(KINCAL_SANITIZE "Build native code with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
# Warnings are errors where we choose the compiler and flags (the test and bench presets, CI); a
# user's build of the main job with another GCC must not fail on a warning that compiler invents.
option(KINCAL_WERROR "Treat warnings on kincal's own code as errors" OFF)

# ccache, when installed, serves unchanged objects again (CI builds three trees; developers rebuild
# often). Paths under the source tree are hashed relative to it, so clones share the cache.
find_program(KINCAL_CCACHE ccache)
if(KINCAL_CCACHE)
  set(kincal_ccache ${CMAKE_COMMAND} -E env CCACHE_BASEDIR=${PROJECT_SOURCE_DIR} CCACHE_NOHASHDIR=1
      ${KINCAL_CCACHE})
  set(CMAKE_C_COMPILER_LAUNCHER ${kincal_ccache})
  set(CMAKE_CXX_COMPILER_LAUNCHER ${kincal_ccache})
endif()

# Strict warnings as errors on our own code (STYLE.md habit 6).
set(KINCAL_WARNINGS
    -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Wdouble-promotion -Wshadow
    -Wold-style-cast -Wcast-align -Wimplicit-fallthrough
    # GCC 12 reports a false -Wrestrict inside libstdc++'s string code for "text" + std::string at
    # -O2/-O3 (GCC bugs 105329, 105651); one switch here rather than one per target.
    -Wno-restrict)
if(KINCAL_WERROR)
  list(APPEND KINCAL_WARNINGS -Werror)
endif()
# GCC's note that the AAPCS changed in GCC 7 concerns only mixing old and new objects.
if(CMAKE_CROSSCOMPILING)
  list(APPEND KINCAL_WARNINGS -Wno-psabi)
endif()

# The same float results, bit for bit, natively and on the Cortex-M4: no contraction of a * b + c
# into a fused multiply-add (C++ lets GCC do it by default; the M4F has VFMA, x86-64's baseline
# has no FMA). Everywhere, not per target: inline geometry (rigid_transform.hpp, link_model.hpp,
# ...) is compiled into every program that includes it, and one COMDAT copy with FMAs could be
# the one the linker keeps. Cost on the host: none, its baseline ISA cannot fuse (the objects are
# the same bytes with and without). On the M4 the hot loops fuse explicitly (firmware/core/
# mul_add.hpp, the same bits on both targets); the rest of the geometry costs up to 16 % more
# instructions than fused (tests/bench/geometry_m4_bench.cpp). Checked by
# m4.geometry_digest_matches_native.
add_compile_options(-ffp-contract=off)

# The test preset runs the tests with ASAN_OPTIONS=intercept_tls_get_addr=0 (CMakePresets.json).
# GCC 12's sanitizer runtime (and LLVM's up to 16) is known to take a dynamic TLS block that
# happens to start 16 bytes into a page for a pre-2.25 glibc one and to read a length before it;
# LeakSanitizer's tracer then dies at exit ("Tracer caught signal 11 ... LeakSanitizer has
# encountered a fatal error") after the test passed. OpenCV's TBB worker threads carry dynamic
# TLS: seen once here, in host_camera_tests.
if(KINCAL_SANITIZE AND NOT CMAKE_CROSSCOMPILING)
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

# Our own code: strict warnings.
function(kincal_strict target)
  target_compile_options(${target} PRIVATE ${KINCAL_WARNINGS})
endfunction()

# Firmware code (natively too): no exceptions, no RTTI, and on the MCU a call graph with
# stack use per function (.ci files) for toolchain/check_stack.py.
function(kincal_firmware target)
  kincal_strict(${target})
  target_compile_options(${target} PRIVATE $<$<COMPILE_LANGUAGE:CXX>:-fno-exceptions -fno-rtti>)
  if(CMAKE_CROSSCOMPILING)
    target_compile_options(${target} PRIVATE -fcallgraph-info=su)
    # ccache 4.7 does not know -fcallgraph-info: a cache hit gives the object without its .ci
    # file, and the stack check then misses it. These objects are always compiled.
    set_target_properties(${target} PROPERTIES C_COMPILER_LAUNCHER "" CXX_COMPILER_LAUNCHER "")
  endif()
endfunction()
