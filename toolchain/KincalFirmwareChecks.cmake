# Firmware discipline for the Cortex-M4 build, as link options and ctest checks:
#   no heap   allocator, operator new/delete and exception entry points are --wrap'ed with no
#             wrapper defined, so using one fails the link and names the caller; plus
#             toolchain/check_no_heap.py over the symbols (libraries and images);
#   stack     toolchain/check_stack.py over GCC's call graphs (-fcallgraph-info=su);
#   size      toolchain/check_size.py over arm-none-eabi-size.

set(KINCAL_NO_HEAP_WRAPS
  malloc free calloc realloc _malloc_r _free_r _calloc_r _realloc_r
  _Znwj _Znaj _ZdlPv _ZdaPv _ZdlPvj _ZdaPvj _ZnwjRKSt9nothrow_t _ZnajRKSt9nothrow_t
  __cxa_allocate_exception __cxa_throw)
list(TRANSFORM KINCAL_NO_HEAP_WRAPS PREPEND "-Wl,--wrap=" OUTPUT_VARIABLE KINCAL_NO_HEAP_LINK_OPTIONS)

# The .ci call graphs GCC writes beside a target's objects: one per C/C++ source. Named from
# the target's sources (not globbed), so a stale file of an earlier build cannot leak in.
# A source outside the target's folder gets CMake's object path: relative, each ".." as "__".
function(kincal_callgraph_files target out)
  get_target_property(dir ${target} BINARY_DIR)
  get_target_property(source_dir ${target} SOURCE_DIR)
  get_target_property(sources ${target} SOURCES)
  set(files)
  foreach(source ${sources})
    if(source MATCHES "\\.(c|cc|cpp)$")
      if(IS_ABSOLUTE ${source})
        file(RELATIVE_PATH source ${source_dir} ${source})
      endif()
      string(REPLACE "../" "__/" source ${source})
      list(APPEND files ${dir}/CMakeFiles/${target}.dir/${source}.ci)
    endif()
  endforeach()
  set(${out} ${files} PARENT_SCOPE)
endfunction()

# A firmware library: its objects must not refer to the heap, and each global function's
# worst stack must fit STACK_BUDGET.
function(kincal_firmware_library_checks target)
  cmake_parse_arguments(ARG "" "STACK_BUDGET" "CALLEES" ${ARGN})
  kincal_callgraph_files(${target} ci_files)
  # CALLEES: firmware libraries the target calls into; their call graphs bound those calls (their
  # functions are not entry points of this check: they have their own).
  foreach(t ${ARG_CALLEES})
    kincal_callgraph_files(${t} files)
    list(APPEND ci_files ${files})
  endforeach()
  add_test(NAME m4.${target}.no_heap
    COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/toolchain/check_no_heap.py
            --nm ${CMAKE_NM} --archive $<TARGET_FILE:${target}>)
  add_test(NAME m4.${target}.stack
    COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/toolchain/check_stack.py --name ${target}
            --budget ${ARG_STACK_BUDGET} --nm ${CMAKE_NM} --entries-from $<TARGET_FILE:${target}> ${ci_files})
  set_tests_properties(m4.${target}.no_heap m4.${target}.stack PROPERTIES LABELS "m4;checks")
endfunction()

# A firmware image: linked with the no-heap wraps; its flash and RAM within budget; the
# worst stack of each STACK_ENTRIES symbol (through LIBRARIES' code too) within STACK_BUDGET.
# WRAPS: symbols the image's own code replaces at link time (--wrap: calls to S go to __wrap_S,
# which reaches the original as __real_S); the stack check follows the calls the same way.
function(kincal_firmware_image target)
  cmake_parse_arguments(ARG "" "FLASH_BUDGET;RAM_BUDGET;STACK_BUDGET" "STACK_ENTRIES;LIBRARIES;WRAPS" ${ARGN})
  list(TRANSFORM ARG_WRAPS PREPEND "-Wl,--wrap=" OUTPUT_VARIABLE wrap_link_options)
  list(TRANSFORM ARG_WRAPS PREPEND "--wrap=" OUTPUT_VARIABLE wrap_stack_options)
  target_link_options(${target} PRIVATE ${KINCAL_NO_HEAP_LINK_OPTIONS} ${wrap_link_options}
    -Wl,-Map=$<TARGET_FILE:${target}>.map)
  target_link_libraries(${target} PRIVATE ${ARG_LIBRARIES})
  # Intel hex, not a flat .bin: a .bin would span gaps in the image (the STM32F407's parameter
  # sectors) with zeros and overwrite whatever a flashing tool finds there.
  add_custom_command(TARGET ${target} POST_BUILD
    COMMAND ${CMAKE_OBJCOPY} -O ihex $<TARGET_FILE:${target}> $<TARGET_FILE_DIR:${target}>/${target}.hex
    COMMENT "Flashable Intel hex ${target}.hex")

  set(ci_files)
  foreach(t ${target} ${ARG_LIBRARIES})
    kincal_callgraph_files(${t} files)
    list(APPEND ci_files ${files})
  endforeach()
  list(TRANSFORM ARG_STACK_ENTRIES PREPEND "--entry=" OUTPUT_VARIABLE entries)

  add_test(NAME m4.${target}.no_heap
    COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/toolchain/check_no_heap.py
            --nm ${CMAKE_NM} --image $<TARGET_FILE:${target}> --map $<TARGET_FILE:${target}>.map)
  add_test(NAME m4.${target}.size
    COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/toolchain/check_size.py --size ${CMAKE_SIZE}
            --flash-budget ${ARG_FLASH_BUDGET} --ram-budget ${ARG_RAM_BUDGET} $<TARGET_FILE:${target}>)
  add_test(NAME m4.${target}.stack
    COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/toolchain/check_stack.py --name ${target}
            --budget ${ARG_STACK_BUDGET} ${entries} ${wrap_stack_options} ${ci_files})
  set_tests_properties(m4.${target}.no_heap m4.${target}.size m4.${target}.stack PROPERTIES LABELS "m4;checks")
endfunction()
