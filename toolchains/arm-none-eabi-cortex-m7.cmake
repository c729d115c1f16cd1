# Bare-metal Cortex-M7 with double-precision FPU (e.g. STM32H7; QEMU's
# mps2-an500).
set(CMAKE_SYSTEM_PROCESSOR cortex-m7)
set(GABARIT_CPU_FLAGS "-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard")
set(GABARIT_QEMU_MACHINE mps2-an500)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
