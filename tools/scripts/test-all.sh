#!/usr/bin/env bash
# The whole test suite — the README's test command and what CI runs:
#   1. host, Debug + AddressSanitizer + UBSan (every test, the CLI end to end)
#   2. host, Release (again, plus the no-heap proof, which replaces malloc)
#   3. aarch64-linux-gnu cross build, every test under qemu-aarch64
#   4. arm-none-eabi Cortex-M7 kernel build and its forbidden-symbol check
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/setup-debian.sh
status=0
for preset in dev release aarch64 cortex-m7; do
  echo "=== $preset ==="
  start=$SECONDS
  if cmake --workflow --preset "$preset" --fresh; then
    echo "=== $preset: ok ($((SECONDS - start)) s) ==="
  else
    echo "=== $preset: FAILED ($((SECONDS - start)) s) ==="
    status=1
  fi
done
exit $status
