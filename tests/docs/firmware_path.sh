#!/usr/bin/env bash
# The README's firmware path, run as a new user runs it: on a copy of the
# source tree with no build/ in it (what a fresh clone holds), the commands of
# README.md's "Using gabarit in your firmware project" that start with
# `cmake --preset cortex-m7` and `cmake --install build/cortex-m7`, taken from
# the README itself so that the test follows the text; then an outside
# project (tests/consumer) built against the installed prefix for Cortex-M7.
# Also: -DGABARIT_KERNEL_ONLY=ON with the Cortex-M7 toolchain file builds the
# kernel alone.
#
# Usage: firmware_path.sh SOURCE_DIR
set -euo pipefail
src=$(cd "${1:?usage: firmware_path.sh SOURCE_DIR}" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
tree=$work/gabarit
mkdir -p "$tree"

# The tree as a clone would have it: the files git tracks (and new files not
# ignored), never build/. Outside a git checkout, everything but build/.
if git -C "$src" rev-parse --show-toplevel > /dev/null 2>&1; then
  (cd "$src" && git ls-files -z --cached --others --exclude-standard |
     while IFS= read -r -d '' f; do [ -e "$f" ] && printf '%s\0' "$f"; done |
     tar --null -T - -cf -) | tar -xf - -C "$tree"
else
  (cd "$src" && tar --exclude=./build -cf - .) | tar -xf - -C "$tree"
fi
[ ! -e "$tree/build" ] || { echo "FAIL: the copy has a build/ directory"; exit 1; }

# The README's commands, as written (the install prefix moved into $work).
mapfile -t commands < <(grep -E '^cmake --(preset cortex-m7|install build/cortex-m7)' "$tree/README.md" | sed -E 's/[[:space:]]+#.*$//')
[ "${#commands[@]}" -ge 2 ] || { echo "FAIL: README.md no longer shows the cortex-m7 configure/build and install commands"; exit 1; }
prefix=$work/prefix
for c in "${commands[@]}"; do
  c=${c//\/opt\/gabarit-m7/$prefix}
  echo "+ $c"
  (cd "$tree" && bash -c "$c") > "$work/step.log" 2>&1 || { tail -40 "$work/step.log"; echo "FAIL: '$c' on a clean tree"; exit 1; }
done
for f in lib/libgabarit_kernel.a lib/cmake/gabarit/gabaritConfig.cmake lib/pkgconfig/gabarit-kernel.pc include/gabarit/tracker.hpp; do
  [ -f "$prefix/$f" ] || { echo "FAIL: $f not installed"; exit 1; }
done
echo "README firmware path: configured, built and installed on a clean tree"

# An outside firmware project consumes the prefix for Cortex-M7.
toolchain=$tree/toolchains/arm-none-eabi-cortex-m7.cmake
cmake -S "$tree/tests/consumer" -B "$work/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_TOOLCHAIN_FILE="$toolchain" -DCMAKE_PREFIX_PATH="$prefix" > "$work/consumer.log" 2>&1 &&
  cmake --build "$work/consumer" >> "$work/consumer.log" 2>&1 ||
  { tail -40 "$work/consumer.log"; echo "FAIL: the consumer did not build against the installed prefix"; exit 1; }
echo "consumer: built and linked for Cortex-M7 against the installed prefix"

# GABARIT_KERNEL_ONLY: the kernel alone, whatever the toolchain.
cmake -S "$tree" -B "$work/kernel-only" -G Ninja -DCMAKE_BUILD_TYPE=MinSizeRel -DCMAKE_TOOLCHAIN_FILE="$toolchain" \
      -DGABARIT_KERNEL_ONLY=ON > "$work/kernel-only.log" 2>&1 &&
  cmake --build "$work/kernel-only" >> "$work/kernel-only.log" 2>&1 ||
  { tail -40 "$work/kernel-only.log"; echo "FAIL: -DGABARIT_KERNEL_ONLY=ON did not build"; exit 1; }
built=$(cd "$work/kernel-only" && find . -name '*.a' -o -name '*.elf' | sort)
[ "$built" = ./kernel/libgabarit_kernel.a ] || { echo "FAIL: GABARIT_KERNEL_ONLY built more than the kernel:"; echo "$built"; exit 1; }
echo "GABARIT_KERNEL_ONLY with the Cortex-M7 toolchain: the kernel alone"
echo "PASS"
