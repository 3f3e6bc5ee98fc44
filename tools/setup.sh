#!/usr/bin/env bash
# Installs the Debian packages rgbdtam needs. With --aarch64 it also installs the cross
# toolchain and qemu-user, and unpacks the arm64 static libpng, zlib and libgpiod into .sysroot/arm64
# (download only: the host's package set is not changed to multiarch).
# With --fuzz it installs clang, whose libFuzzer tools/fuzz.sh uses; with --opencv, OpenCV's
# contrib modules for rgbdtam-vs-opencv.
set -euo pipefail
cd "$(dirname "$0")/.."

aarch64=false
fuzz=false
opencv=false
for arg in "$@"; do
  case "$arg" in
    --aarch64) aarch64=true ;;
    --fuzz) fuzz=true ;;
    --opencv) opencv=true ;;
    *) echo "usage: tools/setup.sh [--aarch64] [--fuzz] [--opencv]" >&2; exit 2 ;;
  esac
done

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

# python3-open3d: the map-export test opens the PLY with it (tools/check_map.py).
# libfreenect-dev: the Kinect v1 backend of the dynamic build, and fakenect for its tests.
# libopenni2-dev: the OpenNI2 backend of the dynamic build, and its Dummy device for tests.
packages=(build-essential cmake libeigen3-dev libpng-dev zlib1g-dev libgpiod-dev googletest file
  python3-open3d libfreenect-dev libopenni2-dev)
# tools/mavlink-check decodes the link with node-mavlink (pinned in its lockfile). A Node that
# is already there (with its npm) is used as it is.
command -v node >/dev/null && command -v npm >/dev/null || packages+=(nodejs npm)
if $aarch64; then packages+=(g++-aarch64-linux-gnu qemu-user); fi
if $fuzz; then packages+=(clang); fi  # libFuzzer ships with Debian's clang
# rgbdtam-vs-opencv (the dynamic build's host benchmark) compares with OpenCV's RgbdOdometry.
if $opencv; then packages+=(libopencv-dev libopencv-contrib-dev); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

if $aarch64 && [ ! -f .sysroot/arm64/usr/lib/aarch64-linux-gnu/libgpiod.a ]; then
  echo "setup: fetching arm64 libpng, zlib and libgpiod into .sysroot/arm64"
  if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    $SUDO dpkg --add-architecture arm64
  fi
  $SUDO apt-get update -qq
  work=$(mktemp -d)
  (cd "$work" && apt-get download -qq libpng-dev:arm64 libpng16-16:arm64 zlib1g-dev:arm64 zlib1g:arm64 \
    libgpiod-dev:arm64 libgpiod2:arm64 2>/dev/null)
  mkdir -p .sysroot/arm64
  for deb in "$work"/*.deb; do dpkg-deb -x "$deb" .sysroot/arm64; done
  rm -rf "$work"
fi
if [ ! -d tools/mavlink-check/node_modules/node-mavlink ]; then
  echo "setup: installing node-mavlink for tools/mavlink-check (npm ci, from its lockfile)"
  (cd tools/mavlink-check && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
fi
echo "setup: done"
