# Shared by the bare-metal Cortex-M toolchain files, which set GABARIT_CPU_FLAGS
# first. Debian's gcc-arm-none-eabi with newlib. The project builds the kernel
# and the firmware in platform/cortex-m for it (no host tools, no GoogleTest;
# CMakeLists.txt); -DGABARIT_KERNEL_ONLY=ON, the kernel alone.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
# -fstack-usage/-fcallgraph-info: per-function frames and the call graph, for
# the worst-case stack report (platform/cortex-m/firmware_report.py).
set(CMAKE_C_FLAGS_INIT "${GABARIT_CPU_FLAGS} -ffunction-sections -fdata-sections -fstack-usage -fcallgraph-info=su")
set(CMAKE_ASM_FLAGS_INIT "${GABARIT_CPU_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT "${CMAKE_C_FLAGS_INIT} -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
