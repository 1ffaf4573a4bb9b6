# Compile options shared by every kincal target; one place to change them.

option(KINCAL_SANITIZE "Build native code with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)

# Strict warnings as errors on our own code (STYLE.md habit 6).
set(KINCAL_WARNINGS
    -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Wdouble-promotion -Wshadow
    -Wold-style-cast -Wcast-align -Wimplicit-fallthrough -Werror)
# GCC's note that the AAPCS changed in GCC 7 concerns only mixing old and new objects.
if(CMAKE_CROSSCOMPILING)
  list(APPEND KINCAL_WARNINGS -Wno-psabi)
endif()

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
  endif()
endfunction()
