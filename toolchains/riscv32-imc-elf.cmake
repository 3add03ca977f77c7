# RV32IMC (no FPU) bare-metal toolchain: the buildable stand-in for Myon's head-board soft core.
# Uses Debian's gcc-riscv64-unknown-elf (a multilib compiler) with -march=rv32imc_zicsr
# -mabi=ilp32. No C or C++ standard library is linked: firmware and tests link only the
# board runtime (hal/board/qemu_virt) and libgcc's integer helpers.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR riscv32)

set(SEQSLAM_CROSS_PREFIX riscv64-unknown-elf- CACHE STRING "Cross compiler prefix")
set(CMAKE_C_COMPILER ${SEQSLAM_CROSS_PREFIX}gcc)
set(CMAKE_CXX_COMPILER ${SEQSLAM_CROSS_PREFIX}g++)
set(CMAKE_ASM_COMPILER ${SEQSLAM_CROSS_PREFIX}gcc)
set(CMAKE_AR ${SEQSLAM_CROSS_PREFIX}ar CACHE FILEPATH "")
set(CMAKE_RANLIB ${SEQSLAM_CROSS_PREFIX}ranlib CACHE FILEPATH "")
set(CMAKE_OBJCOPY ${SEQSLAM_CROSS_PREFIX}objcopy CACHE FILEPATH "")
set(CMAKE_NM ${SEQSLAM_CROSS_PREFIX}nm CACHE FILEPATH "")
set(CMAKE_SIZE ${SEQSLAM_CROSS_PREFIX}size CACHE FILEPATH "")

# Executables cannot link without our startup code, so let CMake's compiler checks build
# static libraries instead.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(SEQSLAM_ARCH_FLAGS "-march=rv32imc_zicsr -mabi=ilp32 -mcmodel=medlow")
set(SEQSLAM_FREESTANDING_FLAGS
    "-ffreestanding -ffunction-sections -fdata-sections -fno-common -fno-tree-loop-distribute-patterns")
set(CMAKE_C_FLAGS_INIT "${SEQSLAM_ARCH_FLAGS} ${SEQSLAM_FREESTANDING_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT
    "${SEQSLAM_ARCH_FLAGS} ${SEQSLAM_FREESTANDING_FLAGS} -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit")
set(CMAKE_ASM_FLAGS_INIT "${SEQSLAM_ARCH_FLAGS}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-nostdlib -nostartfiles -Wl,--gc-sections -Wl,--no-warn-rwx-segments")

# GCC has no rv32imc_zicsr multilib; rv32im/ilp32 is the matching subset (C is only an
# encoding). Link that libgcc explicitly for the few integer helpers (64-bit division).
execute_process(
  COMMAND ${CMAKE_C_COMPILER} -march=rv32im -mabi=ilp32 -print-libgcc-file-name
  OUTPUT_VARIABLE SEQSLAM_LIBGCC OUTPUT_STRIP_TRAILING_WHITESPACE)
set(CMAKE_C_STANDARD_LIBRARIES "${SEQSLAM_LIBGCC}")
set(CMAKE_CXX_STANDARD_LIBRARIES "${SEQSLAM_LIBGCC}")

# Unit tests run under QEMU; the runner maps the board's exit device onto a process status.
set(CMAKE_CROSSCOMPILING_EMULATOR ${CMAKE_CURRENT_LIST_DIR}/../scripts/qemu-run.sh)

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(SEQSLAM_TARGET_BOARD qemu_virt CACHE STRING "Board support package for target builds")
