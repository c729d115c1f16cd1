# 64-bit ARM Linux (Debian's g++-aarch64-linux-gnu), tests under qemu-aarch64.
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(GABARIT_TRIPLE aarch64-linux-gnu)
set(GABARIT_QEMU qemu-aarch64)
include(${CMAKE_CURRENT_LIST_DIR}/linux-gnu-common.cmake)
