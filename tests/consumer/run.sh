#!/usr/bin/env bash
# Builds tests/consumer against gabarit as a firmware project would:
#   run.sh install BUILD_DIR TABLE|- [TOOLCHAIN_FILE]
#       installs BUILD_DIR (a configured and built gabarit) into a temporary
#       prefix, then configures the consumer with find_package against it;
#   run.sh subproject SOURCE_DIR TABLE [TOOLCHAIN_FILE]
#       configures the consumer with FetchContent on the source tree.
# TABLE - (bare metal only): link an empty table.
# Without a toolchain file the program is run and must exit 0; with one
# (bare metal) it must link.
set -euo pipefail
mode=${1:?usage: run.sh install|subproject DIR TABLE [TOOLCHAIN_FILE]}
dir=$(cd "${2:?}" && pwd)
table=${3:?}
[ "$table" = - ] && table="" || table=$(cd "$(dirname "$table")" && pwd)/$(basename "$table")
toolchain=${4:-}
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
args=(-S "$here" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DGABARIT_CONSUMER_TABLE="$table")
[ -n "$toolchain" ] && args+=(-DCMAKE_TOOLCHAIN_FILE="$toolchain")
case $mode in
  install)
    cmake --install "$dir" --prefix "$work/prefix" > "$work/install.log"
    test -f "$work/prefix/lib/cmake/gabarit/gabaritConfig.cmake" || { echo "no gabaritConfig.cmake installed"; exit 1; }
    test -f "$work/prefix/lib/pkgconfig/gabarit-kernel.pc" || { echo "no gabarit-kernel.pc installed"; exit 1; }
    test -f "$work/prefix/include/gabarit/tracker.hpp" || { echo "no headers installed"; exit 1; }
    args+=(-DCMAKE_PREFIX_PATH="$work/prefix")
    ;;
  subproject) args+=(-DGABARIT_CONSUMER_SOURCE="$dir") ;;
  *) echo "unknown mode $mode"; exit 2 ;;
esac
cmake "${args[@]}" > "$work/configure.log" || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/build" > "$work/build.log" || { cat "$work/build.log"; exit 1; }
if [ -z "$toolchain" ]; then
  status=0
  "$work/build/consumer" || status=$?
  [ "$status" = 0 ] || { echo "consumer exited $status (main.cpp lists the codes)"; exit 1; }
  echo "consumer ($mode, host): built and ran"
  if [ "$mode" = install ] && command -v pkg-config > /dev/null; then
    # The same program without CMake, from the pkg-config file alone.
    export PKG_CONFIG_PATH="$work/prefix/lib/pkgconfig"
    # shellcheck disable=SC2046
    c++ -std=c++20 $(pkg-config --cflags gabarit-kernel) "$here/main.cpp" "$work/build/table.S" \
        $(pkg-config --libs gabarit-kernel) -o "$work/consumer-pkg-config"
    "$work/consumer-pkg-config" || { echo "the pkg-config build exited $?"; exit 1; }
    echo "consumer (pkg-config, host): built and ran"
  fi
else
  echo "consumer ($mode, $(basename "$toolchain" .cmake)): built and linked"
fi
