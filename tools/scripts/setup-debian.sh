#!/usr/bin/env bash
# Installs what gabarit needs to build and test on Debian 12 (bookworm).
# Idempotent: skips apt entirely when every package is already installed.
set -euo pipefail
packages=(
  build-essential cmake ninja-build git python3
  googletest libgtest-dev
  g++-aarch64-linux-gnu g++-arm-linux-gnueabihf qemu-user qemu-system-arm
  gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
  libopencv-imgproc-dev   # gabarit bench's peer (matchTemplate); never linked into the tracker
  python3-skimage netpbm  # the real photograph behind the 'watch' shape, converted at run time
  verilator zlib1g-dev    # hardware voter co-simulation (FST waveforms need zlib)
  yosys nextpnr-ice40 fpga-icestorm  # hardware voter synthesis and place-and-route
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi
sudo=""
[ "$(id -u)" = 0 ] || sudo="sudo"
echo "setup: installing ${missing[*]}"
$sudo apt-get -o DPkg::Lock::Timeout=600 update -q
DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=600 install -y -q --no-install-recommends "${missing[@]}"
