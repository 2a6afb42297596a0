#!/usr/bin/env bash
# Install everything the project needs on a Debian machine, idempotently:
#   Debian packages (compilers for the host and the board, CMake, OSMesa for headless MuJoCo rendering),
#   uv (pinned, from PyPI),
#   the Python environment from uv.lock, and the native build of the firmware core and SIL.
set -euo pipefail
cd "$(dirname "$0")/.."

# gcc-arm-none-eabi + newlib: the core cross-compiled for the board's Cortex-M0+ (size, instruction counts, tests)
# clang + libclang-rt-14-dev: the libFuzzer targets with AddressSanitizer/UBSan (tests/fuzz)
APT_PACKAGES=(build-essential cmake libosmesa6 gcc-arm-none-eabi libnewlib-arm-none-eabi clang libclang-rt-14-dev)
UV_VERSION=0.13.8

say() { printf '[setup] %s\n' "$*" >&2; }

missing=()
for pkg in "${APT_PACKAGES[@]}"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if ((${#missing[@]})); then
  say "installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

if ! command -v uv >/dev/null 2>&1 || [ "$(uv --version | awk '{print $2}')" != "$UV_VERSION" ]; then
  say "installing uv $UV_VERSION from PyPI"
  python3 -m pip install --quiet --disable-pip-version-check "uv==$UV_VERSION"
  hash -r
fi
export UV_PYTHON_DOWNLOADS=never

say "Python environment from uv.lock"
uv sync --locked --quiet

say "native build (firmware core, protocol tests, SIL firmware) in build/native"
cmake -S firmware -B build/native -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build/native -j"$(nproc)" >/dev/null
