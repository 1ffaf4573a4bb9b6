#!/bin/sh
# Runs a Cortex-M4 image under QEMU's mps2-an386 with semihosting; the image's exit status
# becomes ours. Usage: qemu-mps2-an386.sh IMAGE.elf [ARG...]
# KINCAL_QEMU_TIMEOUT (seconds, default 600) bounds the run; KINCAL_QEMU_EXTRA adds options
# (e.g. "-icount shift=0" for instruction counting).
set -eu
image=$1
shift
config="enable=on,target=native,arg=$(basename "$image")"
for arg in "$@"; do
  config="$config,arg=$(printf '%s' "$arg" | sed 's/,/,,/g')"  # QEMU escapes ',' as ',,'
done
# shellcheck disable=SC2086  # KINCAL_QEMU_EXTRA is a list of options
exec timeout --kill-after=5 "${KINCAL_QEMU_TIMEOUT:-600}" \
  qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none \
  -semihosting-config "$config" ${KINCAL_QEMU_EXTRA:-} -kernel "$image"
