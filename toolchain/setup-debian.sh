#!/bin/sh
# Installs what kincal needs on Debian 12 that is not installed yet (as root, or through sudo).
# Every dependency and what it is for is listed in README.md; keep the two lists in step.
set -eu

packages="
  cmake ninja-build g++ ccache python3 clang-format
  libeigen3-dev libcli11-dev doctest-dev
  gcc-arm-none-eabi libstdc++-arm-none-eabi-newlib libnewlib-arm-none-eabi qemu-system-arm
  libopencv-dev nlohmann-json3-dev opencv-doc clang libclang-rt-14-dev
  python3-canmatrix can-utils busybox-static cpio qemu-system-x86 linux-image-amd64
  openocd chromium
  libceres-dev libyaml-cpp-dev
  libtinyxml2-dev liburdfdom-dev liburdfdom-tools
"

missing=""
for p in $packages; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0

if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup-debian.sh: run as root to install:$missing" >&2; exit 1; }
  exec sudo "$0"
fi
echo "setup-debian.sh: installing$missing"
export DEBIAN_FRONTEND=noninteractive
apt-get update -q
# shellcheck disable=SC2086  # $missing is a list of package names
apt-get install -y -q --no-install-recommends $missing
