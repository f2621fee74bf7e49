#!/usr/bin/env bash
# Set-up on a fresh Debian machine: system GL (Mesa EGL/llvmpipe), Xvfb for the viewer's
# tests, a virtual environment in .venv with hybrid-mblur and its test tools. Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."

debs=(libegl1 libegl-mesa0 libgl1 libgl1-mesa-dri libglx-mesa0 libgles2 xvfb xauth
      libx11-6 libxrandr2 libxinerama1 libxcursor1 libxi6 libxkbcommon0)
missing=()
for p in "${debs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "setup: installing Debian packages: ${missing[*]}"
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e ".[test]"
# Compile the ray-tracing kernels into their on-disk cache now (~40 s once; seconds when
# cached), so that the first hybrid frame does not wait for the compiler. Not fatal: without
# it the first hybrid frame compiles them (and says so).
.venv/bin/python -m viewer.warmup \
  || echo "setup: the kernel warm-up failed (above); the first hybrid frame will compile them"
