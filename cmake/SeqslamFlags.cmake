# Strict warnings live in one place; every target of this project links seqslam_warnings.
add_library(seqslam_warnings INTERFACE)
target_compile_options(seqslam_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion -Wdouble-promotion
  -Wcast-align -Wnull-dereference -Wformat=2 -Wundef -Wimplicit-fallthrough
  -Wmissing-declarations
  $<$<COMPILE_LANGUAGE:CXX>:-Wold-style-cast -Wnon-virtual-dtor -Woverloaded-virtual
                             -Wextra-semi>
  $<$<AND:$<COMPILE_LANGUAGE:CXX>,$<CXX_COMPILER_ID:GNU>>:-Wuseless-cast>
  $<$<BOOL:${SEQSLAM_WERROR}>:-Werror>)

# Freestanding flags for the core on the host. On the target the toolchain file sets them
# for everything. -nostdinc with only the compiler's own include directory leaves exactly
# the freestanding C headers (stdint.h, stddef.h, ...) visible, so a libc or libstdc++
# include in include/ or src/ fails to compile instead of sneaking in.
add_library(seqslam_freestanding INTERFACE)
if(SEQSLAM_HOST)
  execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=include
                  OUTPUT_VARIABLE _seqslam_cc_include OUTPUT_STRIP_TRAILING_WHITESPACE)
  target_compile_options(seqslam_freestanding INTERFACE
    -ffreestanding -nostdinc -isystem ${_seqslam_cc_include}
    -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit)
endif()

# Target code is built for size (docs/size.md has the study): in Release (the target preset)
# -Os for every library (the preset's -O3 comes first on the command line, so this wins),
# and in every configuration -msave-restore (prologues and epilogues through libgcc's
# __riscv_save_N/__riscv_restore_N) and -mtune=size. Where speed matters the target says so
# after these: src/CMakeLists.txt keeps the core's hot files at -O3 with the default tuning
# and the core without -msave-restore; seqslam_target_executable below keeps the images' own
# sources (firmware mains, benchmark harness, unit tests) as they were.
# Not cached (unlike the toolchain file's CMAKE_<LANG>_FLAGS_INIT), so an existing build
# tree picks a change up on the next configure.
if(NOT SEQSLAM_HOST)
  add_compile_options("$<$<CONFIG:Release>:-Os>"
                      "$<$<COMPILE_LANGUAGE:C,CXX>:-msave-restore;-mtune=size>")
endif()

# seqslam_target_executable(<name> LINKER_SCRIPT <file> SOURCES ... [LIBS ...])
# A bare-metal executable for the target board: startup code and runtime from the board
# library, the given linker script, a link map next to the ELF.
function(seqslam_target_executable name)
  cmake_parse_arguments(ARG "" "LINKER_SCRIPT" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} seqslam_board seqslam_warnings)
  target_link_options(${name} PRIVATE -T${ARG_LINKER_SCRIPT}
                      -Wl,-Map=$<TARGET_FILE:${name}>.map)
  set_target_properties(${name} PROPERTIES SUFFIX ".elf" LINK_DEPENDS ${ARG_LINKER_SCRIPT})
  # The image's own sources keep the build type's speed flags and GCC's default tuning,
  # without the size flags above: the benchmark harness's instructions between the counter
  # reads are part of some figures (docs/performance.md), and the tests stay as they were.
  if(NOT SEQSLAM_HOST)
    target_compile_options(${name} PRIVATE "$<$<CONFIG:Release>:-O3>"
                           "$<$<COMPILE_LANGUAGE:C,CXX>:-mno-save-restore;-mtune=rocket>")
  endif()
endfunction()
