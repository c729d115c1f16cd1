#!/usr/bin/env bash
# Prepares the virtual board's software from Debian's archive, into CACHE:
#   CACHE/vmlinuz           Debian's current arm64 kernel (linux-image-arm64's dependency,
#                           looked up, never hard-coded: old versions leave the archive)
#   CACHE/busybox           busybox-static for arm64
#   CACHE/modules/*.ko      vivid and its dependencies, configfs, the USB gadget side
#                           (dummy_hcd, libcomposite, usb_f_fs), virtio_mmio and virtio_console (the HIL
#                           relay's serial port), and gpio-sim + irq_sim built out of tree
#                           (Debian's kernel builds neither)
#   CACHE/modules/order     insmod order, dependencies first
# Needs: apt-get, dpkg-deb, g++-aarch64-linux-gnu, linux-kbuild-6.1 (host tools
# for the arm64 headers), python3. Re-running with a complete cache does nothing.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cache=$(mkdir -p "$1" && cd "$1" && pwd)
apt_dir=$cache/apt
opts=(-oAPT::Architecture=arm64 -oAPT::Architectures=arm64 -oDir::State::Lists="$apt_dir/lists"
      -oDir::Cache="$apt_dir/cache" -oDir::State::Status=/dev/null -oDebug::NoLocking=1)
mkdir -p "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial" "$apt_dir/debs"

wanted_modules="vivid configfs gpio-sim dummy_hcd libcomposite usb_f_fs virtio_mmio virtio_console"
if [ -f "$cache/modules/order" ] && [ -f "$cache/vmlinuz" ] && [ -f "$cache/busybox" ] &&
   [ "$(cat "$cache/modules/wanted" 2>/dev/null)" = "$wanted_modules" ]; then
  echo "virtual board: cache $cache is complete ($(cat "$cache/kernel-version"))"
  exit 0
fi

echo "virtual board: reading Debian's arm64 package lists"
apt-get "${opts[@]}" -q update > "$apt_dir/update.log" 2>&1 || { cat "$apt_dir/update.log"; exit 1; }
image=$(apt-cache "${opts[@]}" depends linux-image-arm64 | sed -n 's/^ *Depends: \(linux-image-[0-9].*-arm64\)$/\1/p' | head -n1)
[ -n "$image" ] || { echo "virtual board: cannot find linux-image-arm64's kernel package" >&2; exit 1; }
version=${image#linux-image-}            # e.g. 6.1.0-56-arm64
abi=${version%-arm64}                    # 6.1.0-56
series=$(echo "$version" | cut -d. -f1,2)  # 6.1
echo "virtual board: kernel $version"

cd "$apt_dir/debs"
apt-get "${opts[@]}" -q download "$image" busybox-static "linux-headers-$version" "linux-headers-$abi-common" \
  "linux-source-$series" > "$apt_dir/download.log" 2>&1 || { cat "$apt_dir/download.log"; exit 1; }
root=$cache/root
rm -rf "$root" && mkdir -p "$root"
for deb in "linux-image-$version"_*.deb busybox-static_*.deb "linux-headers-$version"_*.deb "linux-headers-$abi-common"_*.deb; do
  dpkg-deb -x "$deb" "$root"
done

# The arm64 headers include their -common half by absolute path and use the
# host's kbuild tools through a relative link: point both inside $root.
headers=$root/usr/src/linux-headers-$version
sed -i "s|^include /usr/src/|include $root/usr/src/|" "$headers/Makefile"
[ -d "/usr/lib/linux-kbuild-$series" ] || { echo "virtual board: install linux-kbuild-$series (host kbuild tools)" >&2; exit 1; }
mkdir -p "$root/usr/lib" && ln -sfn "/usr/lib/linux-kbuild-$series" "$root/usr/lib/linux-kbuild-$series"

# gpio-sim and irq_sim from the matching kernel source. irq_sim.c calls
# irq_to_desc(), which modules cannot use: it goes through the exported
# generic_handle_domain_irq() instead, and gets the MODULE_LICENSE a module needs.
build=$cache/gpio-sim-build
rm -rf "$build" && mkdir -p "$build"
dpkg-deb --fsys-tarfile "linux-source-$series"_*.deb | tar -xO "./usr/src/linux-source-$series.tar.xz" |
  tar -xJ -C "$build" --strip-components=3 "linux-source-$series/drivers/gpio/gpio-sim.c" \
    "linux-source-$series/drivers/gpio/gpiolib.h" "linux-source-$series/kernel/irq/irq_sim.c"
python3 - "$build/irq_sim.c" <<'PY'
import sys
path = sys.argv[1]
src = open(path).read()
old = "\t\tirqnum = irq_find_mapping(work_ctx->domain, offset);\n\t\thandle_simple_irq(irq_to_desc(irqnum));"
if old not in src:
    sys.exit("irq_sim.c: the irq_to_desc() call to replace was not found (kernel source changed?)")
src = src.replace(old, "\t\tgeneric_handle_domain_irq(work_ctx->domain, offset);")
src = src.replace("\tint irqnum;\n\n\twork_ctx = container_of", "\n\twork_ctx = container_of", 1)
open(path, "w").write(src + '\n#include <linux/module.h>\nMODULE_LICENSE("GPL");\n')
PY
echo 'obj-m := irq_sim.o gpio-sim.o' > "$build/Kbuild"
make -s -C "$headers" M="$build" ARCH=arm64 CROSS_COMPILE=aarch64-linux-gnu- modules 2>&1 | grep -v "Skipping BTF" || true
[ -f "$build/gpio-sim.ko" ] && [ -f "$build/irq_sim.ko" ] || { echo "virtual board: building gpio-sim failed" >&2; exit 1; }

rm -rf "$cache/modules" && mkdir -p "$cache/modules"
python3 "$here/module_order.py" "$root/lib/modules/$version" "$build" -- $wanted_modules > "$cache/modules/paths"
while read -r ko; do cp "$ko" "$cache/modules/"; done < "$cache/modules/paths"
sed 's|.*/||' "$cache/modules/paths" > "$cache/modules/order" && rm "$cache/modules/paths"
echo "$wanted_modules" > "$cache/modules/wanted"
cp "$root/boot/vmlinuz-$version" "$cache/vmlinuz"
cp "$root/bin/busybox" "$cache/busybox"
echo "$version" > "$cache/kernel-version"
rm -rf "$root" "$build" "$apt_dir/debs"  # ~300 MB unpacked; the cache keeps only what boots
echo "virtual board: prepared in $cache"
