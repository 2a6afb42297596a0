#!/usr/bin/env bash
# Install everything the project needs on a Debian machine, idempotently:
#   Debian packages (Python with venv, compilers for the host and the board, CMake, OSMesa for headless MuJoCo
#   rendering),
#   uv (pinned, from PyPI, into .tools/uv when no uv of that version is on PATH: a plain Debian 12 has no pip
#   and PEP 668 refuses system-wide installs, so it goes into a virtual environment of its own),
#   the Python environment from uv.lock, and the native build of the firmware core and SIL.
set -euo pipefail
cd "$(dirname "$0")/.."

# gcc-arm-none-eabi + newlib: the core cross-compiled for the board's Cortex-M0+ (size, instruction counts, tests)
# clang + libclang-rt-14-dev: the libFuzzer targets with AddressSanitizer/UBSan (tests/fuzz)
# python3 + python3-venv: a minimal Debian has no Python at all; venv (with its bundled pip) installs uv
# xvfb + libgl1-mesa-dri: a virtual display for the MuJoCo viewer's test (GLFW window, software OpenGL)
APT_PACKAGES=(python3 python3-venv build-essential cmake libosmesa6 gcc-arm-none-eabi libnewlib-arm-none-eabi clang
              libclang-rt-14-dev xvfb libgl1-mesa-dri)
UV_VERSION=0.13.8

say() { printf '[setup] %s\n' "$*" >&2; }

missing=()
for pkg in "${APT_PACKAGES[@]}"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if ((${#missing[@]})); then
  say "installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  # wait for another apt (unattended upgrades, a second setup) instead of failing at once on its lock
  APT=($SUDO apt-get -o DPkg::Lock::Timeout=600 -o Acquire::Retries=3)
  "${APT[@]}" update -qq
  DEBIAN_FRONTEND=noninteractive "${APT[@]}" install -y -qq "${missing[@]}" >/dev/null
fi

# uv: the one on PATH if it is the pinned version, else ours in .tools/uv (run.sh puts it first on PATH)
TOOLS_UV=.tools/uv
uv_version() { "$1" --version 2>/dev/null | awk '{print $2}'; }
# (an existing .tools/uv is always kept at the pinned version: run.sh puts it first on PATH)
if { [ "$(uv_version uv)" != "$UV_VERSION" ] || [ -d "$TOOLS_UV" ]; } &&
   [ "$(uv_version "$TOOLS_UV/bin/uv")" != "$UV_VERSION" ]; then
  say "installing uv $UV_VERSION from PyPI into $TOOLS_UV"
  rm -rf "$TOOLS_UV"
  python3 -m venv "$TOOLS_UV"
  "$TOOLS_UV/bin/python" -m pip install --quiet --disable-pip-version-check "uv==$UV_VERSION"
fi
[ "$(uv_version uv)" = "$UV_VERSION" ] || export PATH="$PWD/$TOOLS_UV/bin:$PATH"
export UV_PYTHON_DOWNLOADS=never

say "Python environment from uv.lock"
uv sync --locked --quiet

say "native build (firmware core, protocol tests, SIL firmware) in build/native"
cmake -S firmware -B build/native -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build/native -j"$(nproc)" >/dev/null
