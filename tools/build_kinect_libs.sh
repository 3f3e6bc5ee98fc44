#!/usr/bin/env bash
# Static libusb-1.0 (without udev: Debian has no libudev.a) and libfreenect for one target
# triplet, built from Debian's own source packages into .deps/<triplet>:
#   lib/libusb-1.0.a, lib/libfreenect.a, include/libusb-1.0/libusb.h, include/libfreenect*.h
#   lib/libfakenect.a  fakenect (libfreenect's recording player) with its freenect_* symbols
#                      renamed fakenect_* (its other globals prefixed fakenect_), so that one firmware holds the USB driver and the
#                      player side by side (sensor.kind = freenect / fakenect).
# Usage: tools/build_kinect_libs.sh <triplet>...  (x86_64-linux-gnu, aarch64-linux-gnu)
# Nothing is vendored: the sources are fetched with apt-get source into .deps/src, once; the
# triplets are built side by side (libusb's configure is one core's work).
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -gt 0 ] || { echo "usage: tools/build_kinect_libs.sh <triplet>..." >&2; exit 2; }
root=$PWD/.deps
stamp_name=.kinect-libs-2
todo=()
for triplet in "$@"; do [ -f "$root/$triplet/$stamp_name" ] || todo+=("$triplet"); done
[ ${#todo[@]} -gt 0 ] || exit 0

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
src=$root/src
mkdir -p "$src"

# deb-src entries derived from the machine's own sources (no host name written here), for this
# run only: removed however it ends, and written and read again by each run that needs them (a
# list left by an interrupted run is no sign that apt read it).
deb_src_list=/etc/apt/sources.list.d/rgbdtam-deb-src.sources
deb_src_read=false
trap '$SUDO rm -f $deb_src_list' EXIT

# Fetches one source package's .dsc and upstream tarball and checks the tarball against the
# .dsc's SHA-256 (libfreenect's Debian tarball is not on the mirror: only upstream is needed).
fetch_source() {
  local package=$1 tarball_glob=$2
  if compgen -G "$src/$tarball_glob" >/dev/null; then return; fi
  if ! $deb_src_read; then
    sed -n 's/^Types: deb$/Types: deb-src/p; /^Types:/!p' /etc/apt/sources.list.d/debian.sources |
      $SUDO tee $deb_src_list >/dev/null
    $SUDO apt-get update -qq
    deb_src_read=true
  fi
  (cd "$src" && apt-get source --download-only -qq "$package" >/dev/null 2>&1 || true)
  local tarball
  tarball=$(compgen -G "$src/$tarball_glob" | head -n 1) ||
    { echo "setup: apt-get source $package fetched no upstream tarball" >&2; exit 1; }
  local name expected
  name=$(basename "$tarball")
  expected=$(awk -v f="$name" '/^Checksums-Sha256:/{s=1;next} /^[^ ]/{s=0} s && $3==f {print $1}' \
    "$src"/"$package"_*.dsc)
  echo "$expected  $tarball" | sha256sum --check --quiet ||
    { echo "setup: $name does not match its .dsc" >&2; exit 1; }
}

fetch_source libusb-1.0 'libusb-1.0_*.orig.tar.bz2'
fetch_source libfreenect 'libfreenect_*.orig.tar.gz'

# In a subshell of its own: its variables, and its temporary folder removed when it ends.
build_for() (
  triplet=$1
  prefix=$root/$triplet
  stamp=$prefix/$stamp_name
  if [ "$triplet" = "$(gcc -dumpmachine)" ]; then
    cross=""
    tool_prefix=""
  else
    cross="--host=$triplet"
    tool_prefix="$triplet-"
  fi
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  echo "setup: building static libusb and libfreenect for $triplet"

  tar -xjf "$src"/libusb-1.0_*.orig.tar.bz2 -C "$work"
  (cd "$work"/libusb-1.0.* &&
    CC=${tool_prefix}gcc CFLAGS="-O2 -fPIC" ./configure -q $cross --prefix="$prefix" \
      --disable-udev --enable-static --disable-shared >/dev/null &&
    make -s -j"$(nproc)" >/dev/null 2>&1 && make -s install >/dev/null)

  tar -xzf "$src"/libfreenect_*.orig.tar.gz -C "$work"
  freenect=$(echo "$work"/libfreenect-*)
  cflags=(-O2 -fPIC -I"$freenect/include" -I"$freenect/src" -I"$prefix/include/libusb-1.0")
  objects=()
  for c in core tilt cameras flags usb_libusb10 registration audio loader; do
    ${tool_prefix}gcc "${cflags[@]}" -c "$freenect/src/$c.c" -o "$work/$c.o"
    objects+=("$work/$c.o")
  done
  mkdir -p "$prefix/lib" "$prefix/include"
  rm -f "$prefix/lib/libfreenect.a" "$prefix/lib/libfakenect.a"
  ${tool_prefix}ar rcs "$prefix/lib/libfreenect.a" "${objects[@]}"
  ${tool_prefix}gcc "${cflags[@]}" -c "$freenect/fakenect/fakenect.c" -o "$work/fakenect.o"
  ${tool_prefix}nm -g --defined-only "$work/fakenect.o" |
    awk 'NF == 3 {r = $3; if (!sub(/^freenect_/, "fakenect_", r)) r = "fakenect_" r; print $3, r}' \
      >"$work/renames"
  ${tool_prefix}objcopy --redefine-syms="$work/renames" "$work/fakenect.o"
  ${tool_prefix}ar rcs "$prefix/lib/libfakenect.a" "$work/fakenect.o"
  cp "$freenect"/include/libfreenect*.h "$prefix/include/"
  touch "$stamp"
)

pids=()
for triplet in "${todo[@]}"; do
  build_for "$triplet" &
  pids+=($!)
done
failed=0
for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
exit "$failed"
