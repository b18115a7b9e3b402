#!/usr/bin/env bash
# Refresh the lock files tools/setup.sh installs: for each Blender line, resolve bpy of that line
# and tools/requirements.txt afresh in a scratch venv and write every installed package's exact
# version to tools/lock/blender-<line>.txt. Run it on purpose (a new bpy, numpy or ruff), review
# the diff, run `make test`, and commit the lock files on their own.
#   tools/lock.sh            # both lines
#   tools/lock.sh 5.2        # one line
set -euo pipefail
cd "$(dirname "$0")/.."
lines="${*:-5.2 4.5}"
for line in $lines; do
  case "$line" in
    5.2) py_minor=3.13 ;;
    4.5) py_minor=3.11 ;;
    *) echo "lock: unknown Blender line '$line' (use 5.2 or 4.5)" >&2; exit 2 ;;
  esac
  python="$(command -v "python$py_minor" || ls -d "${PYENV_ROOT:-$HOME/.pyenv}"/versions/"$py_minor"*/bin/python"$py_minor" | sort -V | tail -1)"
  scratch="$(mktemp -d)"
  "$python" -m venv "$scratch/venv"
  "$scratch/venv/bin/python" -m pip install -q --upgrade pip
  "$scratch/venv/bin/python" -m pip install -q "bpy==$line.*" -r tools/requirements.txt
  {
    echo "# Exact versions the set-up installs for the Blender $line line (tools/setup.sh $line), bpy included."
    echo "# Written by tools/lock.sh from tools/requirements.txt; update deliberately, in a commit of its own."
    echo "pip==$("$scratch/venv/bin/python" -m pip --version | awk '{print $2}')"
    "$scratch/venv/bin/python" -m pip freeze --exclude-editable
  } > "tools/lock/blender-$line.txt"
  rm -rf "$scratch"
  echo "lock: wrote tools/lock/blender-$line.txt"
done
