#!/usr/bin/env bash
# The whole test suite — the README's test command and what CI runs:
#   1. host, Debug + AddressSanitizer + UBSan (every test, the CLI end to end);
#      then clang-14 with ASan + UBSan (float-cast-overflow too), every test
#      again, plus the libFuzzer targets replaying their seed corpora
#   2. host, Release (again, plus the no-heap proof, which replaces malloc)
#      It also writes the cross-target test vectors (build/release/vectors)
#      that the presets below replay, so it runs before them.
#   3. aarch64-linux-gnu and arm-linux-gnueabihf cross builds, every test under qemu-user
#   4. arm-none-eabi Cortex-M7 and Cortex-M55 firmware, run on QEMU's MPS2/MPS3
#      boards, with the symbol, stack and memory checks
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/setup-debian.sh
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
status=0 passed=0 failed=0
for preset in dev fuzz release aarch64 armhf cortex-m7 cortex-m55; do
  echo "=== $preset ==="
  start=$SECONDS
  if cmake --workflow --preset "$preset" --fresh 2>&1 | tee "$logs/$preset.log"; then
    echo "=== $preset: ok ($((SECONDS - start)) s) ==="
  else
    echo "=== $preset: FAILED ($((SECONDS - start)) s) ==="
    status=1
  fi
  # ctest's summary: "NN% tests passed, F tests failed out of T"
  if summary=$(grep -Eo '[0-9]+ tests failed out of [0-9]+' "$logs/$preset.log" | tail -1); then
    f=$(echo "$summary" | awk '{print $1}'); t=$(echo "$summary" | awk '{print $NF}')
    passed=$((passed + t - f)); failed=$((failed + f))
  else
    failed=$((failed + 1))  # the preset did not get as far as testing
  fi
done
echo "=== all presets ==="
echo "$passed passed, $failed failed"
[ "$failed" = 0 ] || status=1
exit $status
