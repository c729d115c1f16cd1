# Shared by the cross Linux toolchain files, which set GABARIT_TRIPLE (the
# Debian cross compiler's prefix and multi-arch directory) and GABARIT_QEMU
# (the qemu-user binary) first. Cross-built tests run through qemu-user: ctest
# prefixes every test executable with the emulator.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_C_COMPILER ${GABARIT_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${GABARIT_TRIPLE}-g++)
set(CMAKE_FIND_ROOT_PATH /usr/${GABARIT_TRIPLE})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/${GABARIT_TRIPLE}/pkgconfig:/usr/share/pkgconfig")
# LD_LIBRARY_PATH as well as -L: once libc6:<arch> is installed multi-arch
# (libgpiod-dev:<arch> pulls it in), -L alone mixes two glibc builds and
# threaded programs hang (PLATFORM-NOTES).
set(CMAKE_CROSSCOMPILING_EMULATOR ${GABARIT_QEMU} -L /usr/${GABARIT_TRIPLE} -E LD_LIBRARY_PATH=/usr/${GABARIT_TRIPLE}/lib)
