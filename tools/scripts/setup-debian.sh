#!/usr/bin/env bash
# Installs what gabarit needs to build and test on Debian 12 (bookworm).
# Idempotent: skips apt entirely when every package is already installed.
set -euo pipefail
packages=(
  build-essential cmake ninja-build git python3
  universal-ctags         # tests/function_length_check.py: function extents
  googletest libgtest-dev
  libeigen3-dev           # the kernel's motion filter (fixed-size Eigen, headers only)
  libhwy-dev              # Google Highway: the kernel's vector feature extraction (headers only)
  g++-aarch64-linux-gnu g++-arm-linux-gnueabihf qemu-user qemu-system-arm
  gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
  libopencv-imgproc-dev   # gabarit bench's peer (matchTemplate); never linked into the tracker
  libopencv-contrib-dev   # gabarit bench --microscope's MOSSE, KCF and CSRT peers
  python3-skimage netpbm  # the real photograph behind the 'watch' shape, converted at run time
  verilator zlib1g-dev    # hardware voter co-simulation (FST waveforms need zlib)
  libgpiod-dev            # the board application's GPIO lines (libgpiod 1.6, the v1 API)
  libusb-1.0-0-dev        # the HIL link's USB host side (harness, the virtual board's relay)
  linux-kbuild-6.1 cpio xz-utils  # the virtual board: gpio-sim built against the arm64 headers, its initramfs
  yosys nextpnr-ice40 fpga-icestorm  # hardware voter synthesis and place-and-route
  z3                      # the SMT solver behind yosys-smtbmc (formal proof of the FIFO)
  clang-14 libfuzzer-14-dev libclang-rt-14-dev  # the fuzz preset: libFuzzer targets, clang's UBSan (float-cast-overflow)
  lava-dispatcher python3-jinja2  # hil.lava.*: gabarit hil lava-job's jobs under LAVA's dispatcher (lava-run)
)
# The board application's libgpiod for the cross targets, and the arm64
# relay's libusb, from Debian's multi-arch packages.
cross_packages=(libgpiod-dev:arm64 libgpiod-dev:armhf libusb-1.0-0-dev:arm64)
missing=()
for p in "${packages[@]}" "${cross_packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi
sudo=""
[ "$(id -u)" = 0 ] || sudo="sudo"
echo "setup: installing ${missing[*]}"
for arch in arm64 armhf; do
  dpkg --print-foreign-architectures | grep -qx "$arch" || $sudo dpkg --add-architecture "$arch"
done
# A mirror mid-sync can fail one index; retry, then go on with what arrived
# (the install below fails clearly if a package is really unavailable).
for attempt in 1 2 3; do
  $sudo apt-get -o DPkg::Lock::Timeout=600 update -q && break
  echo "setup: apt-get update failed (attempt $attempt)"; sleep 5
done
DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=600 install -y -q --no-install-recommends "${missing[@]}"
