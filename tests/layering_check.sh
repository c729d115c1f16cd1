#!/usr/bin/env bash
# Layers point one way (README.md, "Where things are"), one floor per folder:
#   kernel/     includes and links nothing of ours
#   app/        only the kernel
#   platform/   the kernel and app/, never tools/, hil/ or hdl/
#   hdl/sim     (the Verilated voter's C++ harness) the kernel and app/
#   tools/lib/  (host) the kernel and app/, never platform/, hil/ or hdl/
#   hil/        the kernel, app/ and hdl/sim, never tools/ or platform/
#   tools/      (the CLI, the bench) all of the above but platform/
#   tests/      anything (it is the top)
# Checks every quoted #include of every source file in those folders, and the
# link lines of their CMakeLists.txt. Exits non-zero naming each violation.
# --self-test plants a violation in a copy and expects it to be caught.
set -uo pipefail
root=${1:?usage: layering_check.sh SOURCE_DIR [--self-test]}
cd "$root" || exit 2

check() {
  local top=$1 status=0
  # The layer that owns a quoted include: a header under one of the include
  # roots, or a file beside the including one (then its own layer).
  layer_of() {  # include-path including-file
    local inc=$1 from=$2
    if [ -f "$top/kernel/include/$inc" ]; then echo kernel
    elif [ -f "$top/app/include/$inc" ]; then echo app
    elif [ -f "$top/tools/lib/include/$inc" ]; then echo host
    elif [ -f "$top/hil/include/$inc" ]; then echo hil
    elif [ -f "$top/hdl/sim/$inc" ]; then echo hdl
    elif [ -f "$(dirname "$from")/$inc" ]; then layer_of_file "$from"
    else echo other
    fi
  }
  layer_of_file() {  # the layer a source file is in
    case "${1#"$top"/}" in
      tools/lib/*) echo host ;;
      *) echo "${1#"$top"/}" | cut -d/ -f1 ;;
    esac
  }
  allowed() {  # layer dependency
    case "$1:$2" in
      kernel:kernel) return 0 ;;
      app:kernel|app:app) return 0 ;;
      platform:kernel|platform:app|platform:platform|platform:other) return 0 ;;
      hdl:kernel|hdl:app|hdl:hdl|hdl:other) return 0 ;;
      host:kernel|host:app|host:host|host:other) return 0 ;;
      hil:kernel|hil:app|hil:hdl|hil:hil|hil:other) return 0 ;;
      tools:kernel|tools:app|tools:host|tools:hil|tools:hdl|tools:tools|tools:other) return 0 ;;
      tests:*) return 0 ;;
    esac
    return 1
  }
  for top_dir in kernel app platform hdl tools hil tests; do
    while IFS= read -r file; do
      layer=$(layer_of_file "$file")
      while IFS= read -r inc; do
        dep=$(layer_of "$inc" "$file")
        if ! allowed "$layer" "$dep"; then
          echo "layering: ${file#"$top"/} ($layer) includes \"$inc\" ($dep)"
          status=1
        fi
      done < <(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$file")
    done < <(find "$top/$top_dir" -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' -o -name '*.cc' \))
  done
  # Link lines: which of our libraries each layer's CMake files name.
  declare -A owner=(
    [gabarit_kernel]=kernel [gabarit::kernel]=kernel
    [gabarit_app]=app [gabarit::app]=app [gabarit_test_vectors]=app [gabarit::test_vectors]=app
    [gabarit_link]=app [gabarit::link]=app [gabarit_session_profile]=app [gabarit::session_profile]=app
    [gabarit_link_usb]=app [gabarit::link_usb]=app
    [gabarit_host]=host [gabarit::host]=host [gabarit_bench_lib]=tools
    [gabarit_hil]=hil [gabarit::hil]=hil
    [gabarit_board]=platform)
  for layer in kernel app platform hdl tools hil tests; do
    while IFS= read -r cmake; do
      while IFS= read -r name; do
        dep=${owner[$name]:-}
        [ -n "$dep" ] || continue
        if ! allowed "$layer" "$dep"; then
          echo "layering: ${cmake#"$top"/} ($layer) links $name ($dep)"
          status=1
        fi
      done < <(grep -v '^[[:space:]]*#' "$cmake" | grep -E 'target_link_libraries' -A3 | grep -oE 'gabarit(::|_)[a-z_]+' | sort -u)
    done < <(find "$top/$layer" -name CMakeLists.txt)
  done
  return $status
}

if [ "${2:-}" = "--self-test" ]; then
  scratch=$(mktemp -d)
  trap 'rm -rf "$scratch"' EXIT
  cp -r kernel app platform hdl tools hil tests "$scratch"/
  check "$scratch" > /dev/null || { echo "layering self-test: the clean copy already fails"; exit 1; }
  echo '#include "gabarit/host/tables/table_builder.hpp"' >> "$scratch/platform/linux/luma.cpp"
  if check "$scratch" > /dev/null; then echo "layering self-test: a planted platform -> tools include was not caught"; exit 1; fi
  cp platform/linux/luma.cpp "$scratch/platform/linux/luma.cpp"
  echo '#include "gabarit/app/args.hpp"' >> "$scratch/kernel/src/voter.cpp"
  if check "$scratch" > /dev/null; then echo "layering self-test: a planted kernel -> app include was not caught"; exit 1; fi
  cp kernel/src/voter.cpp "$scratch/kernel/src/voter.cpp"
  echo '#include "gabarit/hil/harness.hpp"' >> "$scratch/tools/lib/src/scenes/synth.cpp"
  if check "$scratch" > /dev/null; then echo "layering self-test: a planted host -> hil include was not caught"; exit 1; fi
  cp tools/lib/src/scenes/synth.cpp "$scratch/tools/lib/src/scenes/synth.cpp"
  echo '#include "gabarit/host/scenes/synth.hpp"' >> "$scratch/hil/src/faults.cpp"
  if check "$scratch" > /dev/null; then echo "layering self-test: a planted hil -> tools/lib include was not caught"; exit 1; fi
  cp hil/src/faults.cpp "$scratch/hil/src/faults.cpp"
  echo '#include "gabarit/host/scenes/synth.hpp"' >> "$scratch/hdl/sim/voter_harness.hpp"
  if check "$scratch" > /dev/null; then echo "layering self-test: a planted hdl -> tools/lib include was not caught"; exit 1; fi
  echo "layering self-test: planted violations caught"
  exit 0
fi
if check "$PWD"; then echo "layering: kernel <- app <- {platform, hdl/sim <- hil, tools/lib} <- tools <- tests, no other edges"; else exit 1; fi
