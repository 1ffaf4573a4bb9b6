# From the native build, configure and build this same tree for the Cortex-M4
# (toolchain/arm-none-eabi.cmake) in <build>/m4, and include its tests in this build's ctest:
# the firmware-core cases under QEMU and the no-heap, stack and size checks.
option(KINCAL_M4 "Also build the Cortex-M4 firmware and run its tests under QEMU" ON)
if(NOT KINCAL_M4)
  return()
endif()

find_program(KINCAL_ARM_GXX arm-none-eabi-g++)
find_program(KINCAL_QEMU_ARM qemu-system-arm)
if(NOT KINCAL_ARM_GXX OR NOT KINCAL_QEMU_ARM)
  message(FATAL_ERROR
    "KINCAL_M4 needs arm-none-eabi-g++ and qemu-system-arm (run toolchain/setup-debian.sh), "
    "or configure with -DKINCAL_M4=OFF to skip the Cortex-M4 build and its tests.")
endif()

include(ExternalProject)
set(KINCAL_M4_BINARY_DIR ${CMAKE_BINARY_DIR}/m4)
ExternalProject_Add(kincal_m4
  SOURCE_DIR ${PROJECT_SOURCE_DIR}
  BINARY_DIR ${KINCAL_M4_BINARY_DIR}
  CMAKE_ARGS
    -DCMAKE_TOOLCHAIN_FILE=${PROJECT_SOURCE_DIR}/toolchain/arm-none-eabi.cmake
    -DCMAKE_BUILD_TYPE=MinSizeRel
    # One cross compiler (Debian's, from toolchain/setup-debian.sh): its warnings are errors, and
    # the test and bench presets' cross builds are the same build, which ccache serves once.
    -DKINCAL_WERROR=ON
    -DPython3_EXECUTABLE=${Python3_EXECUTABLE}
  BUILD_COMMAND ${CMAKE_COMMAND} --build ${KINCAL_M4_BINARY_DIR}
  BUILD_ALWAYS ON
  INSTALL_COMMAND ""
  TEST_COMMAND ""
  USES_TERMINAL_BUILD ON)

# The Cortex-M4 benchmarks are built there.
if(TARGET kincal_benchmarks)
  add_dependencies(kincal_benchmarks kincal_m4)
endif()

# ctest reads this file along with the generated CTestTestfile.cmake of this directory.
file(WRITE ${CMAKE_BINARY_DIR}/m4_tests.cmake "subdirs(\"${KINCAL_M4_BINARY_DIR}\")\n")
set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY TEST_INCLUDE_FILES ${CMAKE_BINARY_DIR}/m4_tests.cmake)
