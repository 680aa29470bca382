#!/usr/bin/env bash
# Installs the Debian packages scan2cad needs. Idempotent and non-interactive:
# packages already present are skipped, apt-get update runs only when something is missing.
#   scripts/install-deps.sh            product build + tests
#   scripts/install-deps.sh --bench    also the optional peers the benchmarks compare against
#   scripts/install-deps.sh --fuzz     also clang and its sanitizer/libFuzzer runtimes (fuzz/run.sh)
set -euo pipefail

pkgs=(
  build-essential cmake ninja-build ccache pkg-config git
  libeigen3-dev libpcl-dev libopenmesh-dev libembree-dev libopencv-dev
  libspdlog-dev libfmt-dev nlohmann-json3-dev libcli11-dev libtbb-dev libgmp-dev
  libpng-dev libtiff-dev  # depth frames (core/src/depth_image.cpp)
  libgtest-dev libgmock-dev
  # reconstruct's point search (exact k-nearest / radius; PCL's FLANN syscalls per query)
  libnanoflann-dev
  # hole filling's dense RBF solves (LAPACK with run-time CPU dispatch; the build with locks)
  libopenblas-pthread-dev
  # acquire: USB laser scanners (libusb) and the device tests' emulation (umockdev)
  libusb-1.0-0-dev umockdev libumockdev-dev
  # independent checker used by the tests (CGAL's exact predicates); header-only
  libcgal-dev
  # the report's browser test: headless Chromium driven through ChromeDriver
  chromium chromium-driver
)
for arg in "$@"; do
  case "$arg" in
    --bench) pkgs+=(python3-open3d python3-opencv libopenvdb-dev hyperfine) ;;
    --fuzz) pkgs+=(clang libclang-rt-14-dev) ;;
    *) echo "install-deps: unknown option $arg (--bench, --fuzz)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#pkgs[@]} packages present"
  exit 0
fi

sudo=""
if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
