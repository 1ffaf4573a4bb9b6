#!/bin/sh
# Installs what one of kincal's commands needs on Debian 12 and is not installed yet (as root, or
# through sudo). With no argument: the main job (build kincal and kincal_platform, run the demo).
# `test` and `bench` add what those commands need. Every package and what it is for is listed in
# README.md; keep the two lists in step.
set -eu

main="
  cmake ninja-build g++ ccache python3
  libeigen3-dev libcli11-dev libopencv-dev nlohmann-json3-dev
  libceres-dev libyaml-cpp-dev libtinyxml2-dev libapriltag-dev
"
# The Cortex-M4 cross build and QEMU: the test and the bench commands both build and run it.
m4="gcc-arm-none-eabi libstdc++-arm-none-eabi-newlib libnewlib-arm-none-eabi qemu-system-arm"
test="
  doctest-dev clang-format opencv-doc clang libclang-rt-14-dev
  python3-canmatrix can-utils busybox-static cpio qemu-system-x86 linux-image-amd64
  openocd chromium liburdfdom-dev liburdfdom-tools
"
bench="doctest-dev opencv-doc liburdfdom-dev"

case "${1:-main}" in
  main) packages=$main ;;
  test) packages="$main $m4 $test" ;;
  bench) packages="$main $m4 $bench" ;;
  *) echo "usage: toolchain/setup-debian.sh [main|test|bench]  (default main)" >&2; exit 2 ;;
esac

missing=""
for p in $packages; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0

if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup-debian.sh: run as root to install:$missing" >&2; exit 1; }
  exec sudo "$0" "$@"
fi
echo "setup-debian.sh: installing$missing"
export DEBIAN_FRONTEND=noninteractive
apt-get update -q
# shellcheck disable=SC2086  # $missing is a list of package names
apt-get install -y -q --no-install-recommends $missing
