#!/usr/bin/env bash
# Install the Penumbra extension zip into a Blender user folder of its own, headless, with
# Blender's own extension command (Blender 4.5 and 5.x), and check that the PENUMBRA engine
# registers. The folder is used as BLENDER_USER_RESOURCES: a worker's ~/.config/blender (or a
# user's) is never read or written.
#
#   farm/install-extension.sh [--blender COMMAND] ZIP USER_FOLDER
#
# Then render with that folder:
#   BLENDER_USER_RESOURCES=USER_FOLDER blender -b shot.blend -E PENUMBRA -o /renders/frame_#### -a
#
# The farm job (farm/penumbra-render.yaml) does the same in each session's working directory.
# See docs/farm.md.
set -euo pipefail

blender=blender
if [ "${1:-}" = "--blender" ]; then
  blender=${2:?--blender needs a command}
  shift 2
fi
if [ $# -ne 2 ]; then
  echo "usage: $0 [--blender COMMAND] ZIP USER_FOLDER" >&2
  exit 2
fi
zip=$1 user=$2

fail() {
  echo "install-extension: ERROR: $*" >&2
  exit 1
}

command -v -- "$blender" >/dev/null || fail "the Blender command '$blender' was not found"
[ -f "$zip" ] || fail "$zip does not exist"
[ "$(od -An -tx1 -N4 -- "$zip" | tr -d ' \n')" = 504b0304 ] || fail "$zip is not a zip file"
mkdir -p -- "$user"
export BLENDER_USER_RESOURCES
BLENDER_USER_RESOURCES=$(cd -- "$user" && pwd)

# Installs into the user_default repository of that folder, enables the extension and saves the
# folder's preferences. Its exit status does not tell a failed install: the files and the engine do.
"$blender" --command extension install-file -r user_default -e "$zip" || true
[ -f "$BLENDER_USER_RESOURCES/extensions/user_default/penumbra/blender_manifest.toml" ] ||
  fail "the extension was not installed from $zip (see Blender's messages above)"
"$blender" -b --python-exit-code 1 --python-expr "import bpy; bpy.context.scene.render.engine = 'PENUMBRA'" ||
  fail "the extension is installed in $BLENDER_USER_RESOURCES but Blender has no PENUMBRA render engine"
echo "install-extension: Penumbra installed in $BLENDER_USER_RESOURCES"
