#!/usr/bin/env bash
# Installs the Debian packages Facet needs to build and test, if any is
# missing (a fresh machine has none of them). Runs apt-get update first.
set -euo pipefail
packages=(
  build-essential cmake ninja-build python3
  llvm-19-dev clang-19 libclang-rt-19-dev   # JIT, bitcode math library, sanitizers
  libzstd-dev zlib1g-dev libedit-dev libxml2-dev libffi-dev libcurl4-openssl-dev  # llvm-19-dev's link deps
  libopenimageio-dev openimageio-tools libfmt-dev doctest-dev  # OIIO's CMake config lists the tools
  libopenexr-dev      # the Kulla-Conty table files (EXR through OpenEXR, without OIIO's dependencies)
  fonts-dejavu-core   # the TrueType font `facet render` labels its plots with (OIIO render_text)
  gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user  # tests: link and run `facet build --target aarch64-linux-gnu` objects
  python3-dev python3-numpy pybind11-dev python3-pytest python3-matplotlib  # import facet (for /usr/bin/python3), its tests and examples
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
