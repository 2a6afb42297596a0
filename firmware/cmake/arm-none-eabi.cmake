# CMake toolchain file: the firmware core for the board's MCU (SAMD21G18A, Cortex-M0+, no FPU) with
# Debian's arm-none-eabi-gcc and newlib-nano.
#
#   cmake -S firmware -B build/arm -DCMAKE_TOOLCHAIN_FILE=firmware/cmake/arm-none-eabi.cmake
#   cmake --build build/arm
#
# Builds the core as a static library and links it into a bare-metal ELF with a fake HAL
# (firmware/cmake/arm_tick_harness.c, laid out by samd21g18a.ld) so flash and RAM sizes are real and
# an emulator can count the instructions of one control tick (bench/bench_tick_instructions.py).
# The host-only targets (shared library, SIL, protocol C test) are skipped when cross-compiling.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_AR arm-none-eabi-ar CACHE FILEPATH "archiver")
set(CMAKE_RANLIB arm-none-eabi-ranlib CACHE FILEPATH "ranlib")
set(CMAKE_SIZE arm-none-eabi-size CACHE FILEPATH "size")

# The compiler checks cannot link a program without a startup file: test with a static library.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

# CPU, no exceptions, one section per function/object so the linker drops what nothing calls.
set(RW_ARM_CPU_FLAGS "-mcpu=cortex-m0plus -mthumb -mfloat-abi=soft")
set(CMAKE_C_FLAGS_INIT "${RW_ARM_CPU_FLAGS} -fno-exceptions -ffunction-sections -fdata-sections -fno-common")
set(CMAKE_CXX_FLAGS_INIT "${RW_ARM_CPU_FLAGS} -fno-exceptions -fno-rtti -ffunction-sections -fdata-sections")
# Size-optimised in every configuration (the project defaults to RelWithDebInfo; -g does not reach flash).
# Cache entries, because CMake appends its own -O2/-O3 to the *_INIT values.
set(CMAKE_C_FLAGS_RELWITHDEBINFO "-Os -g -DNDEBUG" CACHE STRING "C flags, RelWithDebInfo")
set(CMAKE_C_FLAGS_RELEASE "-Os -DNDEBUG" CACHE STRING "C flags, Release")
set(CMAKE_C_FLAGS_MINSIZEREL "-Os -DNDEBUG" CACHE STRING "C flags, MinSizeRel")
set(CMAKE_C_FLAGS_DEBUG "-Os -g" CACHE STRING "C flags, Debug")
# newlib-nano, no system calls (nothing may call them: the test checks the symbol table), unused sections dropped.
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=nano.specs --specs=nosys.specs -Wl,--gc-sections")

# Look for libraries and headers in the toolchain's sysroot only, programs on the host.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
