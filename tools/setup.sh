#!/usr/bin/env bash
# Creates .venv/blender-<line> with bpy and tools/requirements.txt (numpy, OpenImageIO, pytest,
# matplotlib, ruff, openjd-cli) at the exact versions of tools/lock/blender-<line>.txt, and makes
# sure Mesa's EGL (headless OpenGL through llvmpipe) is installed. tools/lock.sh refreshes the
# lock files.
#   tools/setup.sh 5.2        # Blender 5.2 line (Python 3.13)
#   tools/setup.sh 4.5        # Blender 4.5 LTS (Python 3.11)
# Re-running is cheap: a venv whose lock file did not change is left alone.
set -euo pipefail
cd "$(dirname "$0")/.."

line="${1:-5.2}"
case "$line" in
  5.2) py_minor=3.13 ;;
  4.5) py_minor=3.11 ;;
  *) echo "setup: unknown Blender line '$line' (use 5.2 or 4.5)" >&2; exit 2 ;;
esac

# --- Mesa EGL --------------------------------------------------------------------------------
egl_packages="libegl1 libegl-mesa0 libgl1-mesa-dri libgbm1"
missing=""
if command -v dpkg-query >/dev/null 2>&1; then
  for p in $egl_packages; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
  done
fi
if [ -n "$missing" ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "setup: installing Mesa EGL packages:$missing"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $missing >/dev/null
  else
    echo "setup: headless GPU drawing needs these Debian packages:$missing" >&2
    echo "setup: install them as root: apt-get install$missing" >&2
    exit 1
  fi
fi

# --- Python ----------------------------------------------------------------------------------
find_python() {
  local root="${PYENV_ROOT:-$HOME/.pyenv}" c
  for c in $(command -v "python$py_minor" 2>/dev/null) \
           $(ls -d "$root"/versions/"$py_minor"* 2>/dev/null | sort -V -r | sed "s|\$|/bin/python$py_minor|"); do
    # pyenv shims exist for versions that are not active: check that the candidate runs.
    if [ -x "$c" ] && "$c" -c "import sys; assert sys.version_info[:2] == tuple(map(int, '$py_minor'.split('.')))" 2>/dev/null; then
      echo "$c"; return
    fi
  done
}
python="$(find_python || true)"
if [ -z "$python" ]; then
  echo "setup: Blender $line needs Python $py_minor; none found on PATH or in pyenv" >&2
  echo "setup: install it (e.g. 'pyenv install $py_minor') and run again" >&2
  exit 1
fi

venv=".venv/blender-$line"
lock="tools/lock/blender-$line.txt"
stamp="$venv/.requirements"
want="$(cat "$lock") $("$python" --version 2>&1)"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ] && [ -x "$venv/bin/python" ]; then
  exit 0
fi
echo "setup: creating $venv with $python ($lock)"
rm -rf "$venv"
"$python" -m venv "$venv"
"$venv/bin/python" -m pip install -q --disable-pip-version-check "$(grep '^pip==' "$lock")"
# Every package at its locked version; --no-deps: the lock lists the dependencies too, so
# nothing unlisted (and unpinned) comes in.
"$venv/bin/python" -m pip install -q --disable-pip-version-check --no-deps -r "$lock"
# A lock that misses a dependency fails here, not in a test. (pip check also calls bpy 4.5's
# wheel "not supported on this platform", from its tags alone: that line is not a failure.)
broken="$("$venv/bin/python" -m pip check 2>&1 | grep -v "is not supported on this platform" | grep -v "^No broken" || true)"
if [ -n "$broken" ]; then
  echo "setup: $lock is incomplete:" >&2; echo "$broken" >&2; exit 1
fi
echo "$want" > "$stamp"
