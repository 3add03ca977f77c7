# MicroBlaze (Myon's original head-board soft core: 72 MHz, no FPU, 65 456 bytes of memory).
#
# UNTESTED. No MicroBlaze compiler or emulator is available on the machines this project is
# built and tested on (Debian ships none), so this file has never been used to build anything.
# It records the intended flags for someone with Xilinx's microblaze-xilinx-elf-gcc:
#   cmake -B build/microblaze -DCMAKE_TOOLCHAIN_FILE=toolchains/microblaze-elf.cmake
# A MicroBlaze board support package (startup, linker script, console) does not exist yet;
# SEQSLAM_TARGET_BOARD must name one before firmware can link. The core library itself has no
# board dependency and should build as is.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR microblaze)

set(SEQSLAM_CROSS_PREFIX microblaze-xilinx-elf- CACHE STRING "Cross compiler prefix")
set(CMAKE_C_COMPILER ${SEQSLAM_CROSS_PREFIX}gcc)
set(CMAKE_CXX_COMPILER ${SEQSLAM_CROSS_PREFIX}g++)
set(CMAKE_ASM_COMPILER ${SEQSLAM_CROSS_PREFIX}gcc)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

# Myon's configuration: barrel shifter and hardware multiplier, no divider, no FPU.
set(SEQSLAM_ARCH_FLAGS "-mxl-barrel-shift -mno-xl-soft-mul -mxl-soft-div -mcpu=v9.6")
set(SEQSLAM_FREESTANDING_FLAGS "-ffreestanding -ffunction-sections -fdata-sections -fno-common")
set(CMAKE_C_FLAGS_INIT "${SEQSLAM_ARCH_FLAGS} ${SEQSLAM_FREESTANDING_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT
    "${SEQSLAM_ARCH_FLAGS} ${SEQSLAM_FREESTANDING_FLAGS} -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-nostdlib -nostartfiles -Wl,--gc-sections")
set(SEQSLAM_TARGET_BOARD none CACHE STRING "Board support package for target builds")
