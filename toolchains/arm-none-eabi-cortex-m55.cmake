# Bare-metal Cortex-M55 (Armv8.1-M with FPU; QEMU's mps3-an547). Helium (MVE)
# is left to the compiler's choice; the kernel has no hand-written vector code.
set(CMAKE_SYSTEM_PROCESSOR cortex-m55)
set(GABARIT_CPU_FLAGS "-mcpu=cortex-m55 -mthumb -mfloat-abi=hard")
set(GABARIT_QEMU_MACHINE mps3-an547)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
