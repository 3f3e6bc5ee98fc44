#!/usr/bin/env bash
# Installs the Debian packages rgbdtam needs. With --aarch64 it also installs the cross
# toolchain and qemu-user, and unpacks the arm64 static libpng, zlib, libgpiod and GoogleTest into
# .sysroot/arm64
# (download only: the host's package set is not changed to multiarch).
# With --fuzz it installs clang, whose libFuzzer tools/fuzz.sh uses; with --opencv, OpenCV's
# contrib modules for rgbdtam-vs-opencv; with --browser, Debian's Chromium for the monitor's
# page test and openssh for the HIL runner's loopback test; with --cost, valgrind and LLVM (its
# llvm-mca) for tools/aarch64_cost.sh.
# Always: static libusb (without udev) and libfreenect (with fakenect) built from Debian's
# source packages into .deps/<triplet> for the static firmware's Kinect v1 backend
# (tools/build_kinect_libs.sh), for aarch64 too with --aarch64.
set -euo pipefail
cd "$(dirname "$0")/.."

aarch64=false
fuzz=false
opencv=false
browser=false
cost=false
for arg in "$@"; do
  case "$arg" in
    --aarch64) aarch64=true ;;
    --fuzz) fuzz=true ;;
    --opencv) opencv=true ;;
    --browser) browser=true ;;
    --cost) cost=true ;;
    *) echo "usage: tools/setup.sh [--aarch64] [--fuzz] [--opencv] [--browser] [--cost]" >&2; exit 2 ;;
  esac
done

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

# python3-open3d: the map-export test opens the PLY with it (tools/check_map.py).
# libfreenect-dev: the Kinect v1 backend of the dynamic build, and fakenect for its tests.
# libopenni2-dev: the OpenNI2 backend of the dynamic build, and its Dummy device for tests.
# libjpeg62-turbo-dev: MJPEG colour from UVC cameras (libjpeg-turbo's static libjpeg.a);
# libmicrohttpd-dev: the monitor's live page.
# liboctomap-dev: rgbdtam-octomap (host only); octomap-tools: OctoMap's own tools open its files.
# libgtest-dev: GoogleTest (its arm64 package goes into the sysroot for cross builds).
packages=(build-essential cmake ninja-build libeigen3-dev libpng-dev zlib1g-dev libgpiod-dev
  libgtest-dev file python3-open3d libfreenect-dev libopenni2-dev libjpeg62-turbo-dev
  libmicrohttpd-dev liboctomap-dev octomap-tools)
# tools/mavlink-check decodes the link with node-mavlink and drives Chromium with
# playwright-core (both pinned in its lockfile). A Node that is already there (with its npm) is
# used as it is.
command -v node >/dev/null && command -v npm >/dev/null || packages+=(nodejs npm)
if $aarch64; then packages+=(g++-aarch64-linux-gnu qemu-user); fi
if $fuzz; then packages+=(clang); fi  # libFuzzer ships with Debian's clang
if $cost; then packages+=(valgrind llvm llvm-19); fi
# rgbdtam-vs-opencv (the dynamic build's host benchmark) compares with OpenCV's RgbdOdometry.
if $opencv; then packages+=(libopencv-dev libopencv-contrib-dev); fi
if $browser; then packages+=(chromium openssh-server openssh-client); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

# The arm64 sysroot: static libraries for the static firmware, and OpenNI2 with what its
# shared libraries need for the dynamic one (board radxa-rock-5b).
if $aarch64 && [ ! -f .sysroot/arm64/usr/lib/aarch64-linux-gnu/libgtest.a ]; then
  echo "setup: fetching arm64 libpng, zlib, libgpiod, libjpeg-turbo, OpenNI2 and GoogleTest into .sysroot/arm64"
  if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    $SUDO dpkg --add-architecture arm64
  fi
  $SUDO apt-get update -qq
  work=$(mktemp -d)
  (cd "$work" && apt-get download -qq libpng-dev:arm64 libpng16-16:arm64 zlib1g-dev:arm64 zlib1g:arm64 \
    libgpiod-dev:arm64 libgpiod2:arm64 libjpeg62-turbo-dev:arm64 \
    libopenni2-dev:arm64 libopenni2-0:arm64 libjpeg62-turbo:arm64 libusb-1.0-0:arm64 \
    libudev1:arm64 libgtest-dev:arm64 2>/dev/null)
  mkdir -p .sysroot/arm64
  for deb in "$work"/*.deb; do dpkg-deb -x "$deb" .sysroot/arm64; done
  rm -rf "$work"
fi
kinect_triplets=(x86_64-linux-gnu)
if $aarch64; then kinect_triplets+=(aarch64-linux-gnu); fi
tools/build_kinect_libs.sh "${kinect_triplets[@]}"
if [ ! -d tools/mavlink-check/node_modules/node-mavlink ] ||
  [ ! -d tools/mavlink-check/node_modules/playwright-core ]; then
  echo "setup: installing node-mavlink and playwright-core for tools/mavlink-check (npm ci, from its lockfile)"
  (cd tools/mavlink-check && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
fi
echo "setup: done"
