# 32-bit ARM Linux, hard-float (Debian's g++-arm-linux-gnueabihf: ARMv7-A,
# Thumb-2, VFPv3-D16), tests under qemu-arm.
set(CMAKE_SYSTEM_PROCESSOR armv7l)
set(GABARIT_TRIPLE arm-linux-gnueabihf)
set(GABARIT_QEMU qemu-arm)
include(${CMAKE_CURRENT_LIST_DIR}/linux-gnu-common.cmake)
