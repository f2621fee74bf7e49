#!/usr/bin/env bash
# Set-up on a fresh Debian machine: system GL (Mesa EGL/llvmpipe), Xvfb for the viewer's
# tests, a virtual environment in .venv with hybrid-mblur and its test tools. Idempotent:
# a second run installs nothing that is current and compiles nothing that is cached.
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
  # Another apt-get (an unattended upgrade) may hold the package lock: wait for it.
  lock=(-o DPkg::Lock::Timeout=600)
  $sudo apt-get "${lock[@]}" update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get "${lock[@]}" install -y -q \
    --no-install-recommends "${missing[@]}"
fi

if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
# The editable install follows the source by itself; it is redone only when what it was
# made from changes (pyproject.toml, the Python), recorded in a stamp inside .venv.
stamp=.venv/.hmblur-install
want="$(sha256sum pyproject.toml | cut -d' ' -f1) $(.venv/bin/python -c 'import sys; print(sys.version)' | head -1)"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -e ".[test]"
  printf '%s\n' "$want" > "$stamp"
else
  echo "setup: .venv is current (pyproject.toml unchanged): no install"
fi
# Compile every mode's numba kernels into their on-disk cache now (~40 s once; seconds
# when cached), so that no first frame waits for the compiler. Not fatal: without it the
# first frame compiles them (and says so).
.venv/bin/python -m viewer.cli.warmup \
  || echo "setup: the kernel warm-up failed (above); the first frame will compile the kernels"
echo "setup: done; the command is .venv/bin/hmblur ('. .venv/bin/activate' puts hmblur on the PATH)"
