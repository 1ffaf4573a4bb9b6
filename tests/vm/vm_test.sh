#!/bin/bash
# The real-kernel SocketCAN test: boots Debian's linux-image-amd64 under qemu-system-x86_64 with
# software emulation (TCG) and a small initramfs (busybox-static, can-utils and their shared
# libraries, the CAN modules, our binaries and tests/vm/init.sh as /init), then reads the
# VMTEST lines init.sh prints on the serial console.
#   vm_test.sh PLATFORM_BINARY KINCAL_BINARY WORK_DIR
# Exit 0 when every check passed; otherwise 1 and the console log. Progress lines (VMTEST step)
# are printed as the VM runs. Bounded by KINCAL_VM_TIMEOUT (seconds, default 540: about 100 s on
# an idle 2-core machine, 2-3x that when another program keeps a core busy).
set -euo pipefail
platform=$1 kincal=$2 work=$3
here=$(cd "$(dirname "$0")" && pwd)
die() { echo "vm_test: $*" >&2; exit 1; }

kernel=$(ls -1 /boot/vmlinuz-*-amd64 2>/dev/null | sort -V | tail -1 || true)
[ -n "$kernel" ] || die "no /boot/vmlinuz-*-amd64: install linux-image-amd64 (toolchain/setup-debian.sh)"
version=${kernel#/boot/vmlinuz-}
modules=/lib/modules/$version/kernel
[ -d "$modules" ] || die "no $modules for kernel $version"
for tool in qemu-system-x86_64 cpio busybox candump cansend cangen isotpsend isotprecv; do
  command -v "$tool" >/dev/null || die "$tool not found (toolchain/setup-debian.sh installs it)"
done
busybox_bin=$(command -v busybox)
if ldd "$busybox_bin" >/dev/null 2>&1; then die "$busybox_bin is not static: install busybox-static"; fi

root=$work/root
rm -rf "$work"
mkdir -p "$root"/{bin,usr/bin,modules,proc,sys,dev,tmp,vm}
cp "$busybox_bin" "$root/bin/busybox"
# Binaries (without debug info: the sanitized kincal carries ~200 MB of it) and every shared
# library they load, at the same paths.
copy_with_libs() {
  cp "$1" "$root/usr/bin/"
  strip --strip-debug "$root/usr/bin/$(basename "$1")"
  ldd "$1" | grep -o '/[^ ]*' | while read -r lib; do
    mkdir -p "$root$(dirname "$lib")"
    cp -L "$lib" "$root$lib"
  done
}
for tool in candump cansend cangen isotpsend isotprecv; do copy_with_libs "$(command -v $tool)"; done
copy_with_libs "$platform"
copy_with_libs "$kincal"
cp "$modules/net/can/can.ko" "$modules/net/can/can-raw.ko" "$modules/net/can/can-isotp.ko" \
   "$modules/drivers/net/can/dev/can-dev.ko" "$modules/drivers/net/can/vcan.ko" "$root/modules/"
# The virtual V4L2 capture driver vivid and the media modules it needs (the live-camera check).
for m in media/mc/mc media/v4l2-core/videodev media/v4l2-core/v4l2-dv-timings media/common/videobuf2/videobuf2-common \
  media/common/videobuf2/videobuf2-memops media/common/videobuf2/videobuf2-v4l2 media/common/videobuf2/videobuf2-vmalloc \
  media/common/videobuf2/videobuf2-dma-contig media/common/v4l2-tpg/v4l2-tpg media/rc/rc-core media/cec/core/cec \
  media/test-drivers/vivid/vivid; do
  cp "$modules/drivers/$m.ko" "$root/modules/" || die "no $modules/drivers/$m.ko (the live-camera check needs vivid)"
done
cp "$here/init.sh" "$root/init"
chmod +x "$root/init"

# A ParameterWrite of camera intrinsics for isotpsend, and the ParameterData isotprecv must print.
python3 - "$root/vm" <<'PY'
import struct, sys, zlib
payload = struct.pack("<9f2H", 810.5, 811.25, 319.5, 239.5, -0.12, 0.03, 1e-4, -2e-4, 0.0, 640, 480)
version = 4  # shared/parameters.hpp kBlockFormatVersion
header = lambda t: struct.pack("<BBHHI", t, 1, version, len(payload), zlib.crc32(payload))
hexline = lambda b: " ".join("%02X" % x for x in b)
open(sys.argv[1] + "/intrinsics_write.hex", "w").write(hexline(header(0x01) + payload) + "\n")
open(sys.argv[1] + "/intrinsics_data.txt", "w").write(hexline(header(0x82) + payload) + " \n")
PY

# The integrator's files for `kincal platform load`: a camera calibration as `kincal camera
# calibrate` writes it (OpenCV YAML) and a platform.yaml.
cp "$here/../host/session/platform_example.yaml" "$root/vm/platform.yaml"
cat >"$root/vm/camera.yaml" <<'YAML'
%YAML:1.0
---
image_width: 640
image_height: 480
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 600., 0., 319.5, 0., 600., 239.5, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ -0.05, 0.01, 0., 0., 0. ]
YAML

(cd "$root" && find . | cpio -o -H newc --quiet | gzip -1) >"$work/initramfs.gz"
log=$work/console.log
timeout_s=${KINCAL_VM_TIMEOUT:-540}
echo "vm_test: initramfs ready after $SECONDS s; booting $kernel (TCG, timeout $timeout_s s)"
# The console goes to the log and, as it comes, the progress and result lines to our output: a
# run cut off by ctest's timeout still shows how far it got.
set +e
timeout --kill-after=5 "$timeout_s" qemu-system-x86_64 -accel tcg -m 2048 -smp 1 -nographic \
  -no-reboot -kernel "$kernel" -initrd "$work/initramfs.gz" \
  -append "console=ttyS0 quiet loglevel=3 panic=-1 rdinit=/init" 2>&1 |
  sed -u 's/\r$//' | tee "$log.txt" | grep --line-buffered -E "^(VMTEST|flood:|candump log:|scenario:|/tmp/ex)"
qemu_status=${PIPESTATUS[0]}
set -e
echo "vm_test: the VM ended after $SECONDS s (qemu exit $qemu_status)"
if [ $qemu_status -ne 0 ] || ! grep -q "^VMTEST DONE" "$log.txt" || grep -q "^VMTEST FAIL" "$log.txt"; then
  echo "vm_test: FAILED (qemu exit $qemu_status); console log $log.txt:"
  cat "$log.txt"
  exit 1
fi
echo "vm_test: $(grep -c '^VMTEST ok' "$log.txt") checks passed"
