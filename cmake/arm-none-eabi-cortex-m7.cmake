# CMake toolchain file: bare-metal Cortex-M7 with double-precision FPU (e.g. STM32H7), Debian's
# gcc-arm-none-eabi with newlib (libnewlib-arm-none-eabi, libstdc++-arm-none-eabi-newlib), no OS.
# Used by the configure preset arm-cortex-m7 (docs/baremetal.md).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_AR arm-none-eabi-ar CACHE FILEPATH "")
set(CMAKE_RANLIB arm-none-eabi-ranlib CACHE FILEPATH "")
set(SDINS_ARM_SIZE arm-none-eabi-size CACHE FILEPATH "arm-none-eabi-size")
# The compiler checks only compile: linking needs the startup code and linker script of a target.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(SDINS_ARM_CPU_FLAGS "-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard")
set(CMAKE_C_FLAGS_INIT "${SDINS_ARM_CPU_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_CXX_FLAGS_INIT
    "${SDINS_ARM_CPU_FLAGS} -ffunction-sections -fdata-sections -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit")
set(CMAKE_ASM_FLAGS_INIT "${SDINS_ARM_CPU_FLAGS}")
# newlib-nano, no system calls (libnosys), unused sections dropped.
set(CMAKE_EXE_LINKER_FLAGS_INIT "${SDINS_ARM_CPU_FLAGS} --specs=nano.specs --specs=nosys.specs -Wl,--gc-sections")
# Flight builds: -O2 (Release's -O3 mostly adds code size on a microcontroller).
set(CMAKE_C_FLAGS_RELEASE_INIT "-O2 -DNDEBUG")
set(CMAKE_CXX_FLAGS_RELEASE_INIT "-O2 -DNDEBUG")

# Programs from the host; Eigen (header-only, architecture-independent) from the host's CMake packages.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
