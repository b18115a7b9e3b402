"""A test stand-in for the ``blender`` command: the ``bpy`` module driven by the subset of
Blender's command-line arguments that the farm job template (``farm/penumbra-render.yaml``)
and ``farm/install-extension.sh`` use. No ``blender`` binary exists where the tests run; on a
farm the real ``blender`` runs the same command lines.

    python -m devkit.blender_cli -b scene.blend -E PENUMBRA -o //out/frame_#### -s 1 -e 2 -a
    python -m devkit.blender_cli --command extension install-file -r user_default -e penumbra-0.1.0.zip

As in Blender, arguments are processed in order (``-o``, ``-E``, ``-s`` and ``-e`` act on the
loaded file and must precede ``-a``), and the user folders come from the environment
(``BLENDER_USER_RESOURCES`` and the like, which bpy reads itself). Supported:

``-b`` / ``--background``                always the case here
``FILE.blend``                           open the file (an unreadable one ends the run, status 1)
``-E`` / ``--engine ID``                 render engine of the scene (unknown: message, status 1)
``-o`` / ``--render-output PATH``        output path (``#`` for the frame number, ``//`` relative)
``-s`` / ``-e`` / ``-j N``               frame start, end, step
``-a`` / ``--render-anim``               render start..end, writing every frame
``-f`` / ``--render-frame N[,M..][a..b]`` render and write those frames
``-P`` / ``--python FILE``, ``--python-expr EXPR``, ``--python-exit-code N``
``-c`` / ``--command extension ...``     Blender's own ``extension`` command (from its ``bl_pkg``
                                         add-on): ``install-file -r REPO -e ZIP`` runs
                                         ``bpy.ops.extensions.package_install_files`` and saves
                                         the preferences
``--``                                   the rest is left to scripts (``sys.argv``)

Blender's start-up reads the user's preferences (enabling the add-ons and extensions saved
there); the bpy module starts from factory settings, so this entry reads them first. Anything
else is refused with a message (status 2) rather than ignored.

``stand_in_command(folder)`` writes an executable ``blender`` script running this module with
the current interpreter, for tools that take a Blender command.
"""

import shlex
import sys
import traceback
from pathlib import Path

from devkit.session import ROOT, run


class Exit(Exception):
    """Stop processing arguments and leave with ``status``."""

    def __init__(self, status):
        super().__init__(status)
        self.status = status


def _error(message):
    print(f"Error: {message}", file=sys.stderr, flush=True)


def _int(flag, value):
    try:
        return int(value)
    except ValueError:
        _error(f"'{flag}' expects an integer, got '{value}'")
        raise Exit(1) from None


def _frames(spec):
    """Frames of ``-f``: ``N``, ``a..b`` and comma-separated lists of them."""
    frames = []
    for part in spec.split(","):
        first, sep, last = part.partition("..")
        a = _int("-f", first)
        frames.extend(range(a, _int("-f", last) + 1) if sep else [a])
    return frames


class Blender:
    """The state Blender keeps while it processes its arguments."""

    def __init__(self, argv):
        self.argv = ["blender", *argv]
        self.python_exit_code = 0  # Blender's default: a script error does not end the run
        self.file_loaded = False

    # --- scripts --------------------------------------------------------------------------

    def run_python(self, source, filename):
        namespace = {"__name__": "__main__", "__file__": filename, "__builtins__": __builtins__}
        try:
            exec(compile(source, filename, "exec"), namespace)
        except SystemExit as exc:  # sys.exit() in a script ends Blender with that status
            code = exc.code
            if code is not None and not isinstance(code, int):
                print(code, file=sys.stderr)
                code = 1
            raise Exit(code or 0) from None
        except Exception:
            traceback.print_exc()
            if self.python_exit_code:
                raise Exit(self.python_exit_code) from None

    # --- the scene ------------------------------------------------------------------------

    def scene(self, flag):
        import bpy

        if not self.file_loaded:
            _error(f"no blend loaded, cannot use '{flag}' (order the arguments so it follows the file)")
            raise Exit(1)
        return bpy.context.scene

    def open(self, path):
        import bpy

        try:
            bpy.ops.wm.open_mainfile(filepath=str(Path(path).absolute()), load_ui=False)
        except RuntimeError:  # the operator has printed why
            raise Exit(1) from None
        self.file_loaded = True

    def set_engine(self, engine):
        scene = self.scene("-E")
        try:
            scene.render.engine = engine
        except TypeError:
            _error(f"engine not found '{engine}'")
            raise Exit(1) from None

    def render_animation(self):
        import bpy

        self.scene("-a")
        try:
            bpy.ops.render.render(animation=True)
        except RuntimeError as exc:  # Blender reports the engine's error and goes on
            _error(str(exc))

    def render_frames(self, frames):
        """Each frame as Blender's ``-f`` renders it: an animation of that one frame (the output
        path's #s become its number); the scene's frame range is left as it was."""
        import bpy

        scene = self.scene("-f")
        for frame in frames:
            start, end = scene.frame_start, scene.frame_end
            scene.frame_start = scene.frame_end = frame
            try:
                bpy.ops.render.render(animation=True)
            except RuntimeError as exc:
                _error(str(exc))
            finally:
                scene.frame_start, scene.frame_end = start, end

    # --- the command line -----------------------------------------------------------------

    def run(self, args):
        import bpy

        # Blender's start-up: the user's preferences, with the add-ons and extensions they enable.
        bpy.ops.wm.read_userpref()
        args = list(args)
        while args:
            arg = args.pop(0)

            def value():
                if not args:
                    _error(f"'{arg}' expects a value")
                    raise Exit(1)
                return args.pop(0)

            if arg in ("-b", "--background"):
                pass
            elif arg == "--":
                break
            elif arg in ("-c", "--command"):
                return self.command(value(), args)
            elif arg == "--python-exit-code":
                self.python_exit_code = _int(arg, value())
            elif arg in ("-P", "--python"):
                path = value()
                self.run_python(Path(path).read_text(), path)
            elif arg == "--python-expr":
                self.run_python(value(), "<string>")
            elif arg in ("-E", "--engine"):
                self.set_engine(value())
            elif arg in ("-o", "--render-output"):
                self.scene(arg).render.filepath = value()
            elif arg in ("-s", "--frame-start"):
                self.scene(arg).frame_start = _int(arg, value())
            elif arg in ("-e", "--frame-end"):
                self.scene(arg).frame_end = _int(arg, value())
            elif arg in ("-j", "--frame-jump"):
                self.scene(arg).frame_step = _int(arg, value())
            elif arg in ("-a", "--render-anim"):
                self.render_animation()
            elif arg in ("-f", "--render-frame"):
                self.render_frames(_frames(value()))
            elif arg.startswith("-"):
                _error(f"'{arg}' is not supported by this stand-in for blender (devkit/blender_cli.py)")
                raise Exit(2)
            else:
                self.open(arg)
        return 0

    def command(self, name, args):
        """``--command NAME ARGS...``: Blender's command handlers take every argument left."""
        if name != "extension":
            _error(f"'--command {name}' is not supported by this stand-in (only 'extension')")
            return 2
        from bl_pkg.bl_extension_cli import cli_extension_handler

        return cli_extension_handler(args)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    blender = Blender(argv)
    # Scripts see Blender's own argv; the bpy module would otherwise parse none of it.
    sys.argv = blender.argv
    try:
        return blender.run(argv)
    except Exit as exc:
        return exc.status


def stand_in_command(folder, python=None):
    """Write ``folder/blender``, an executable running this module with ``python`` (default:
    this interpreter) and the repository on PYTHONPATH; return its path."""
    python = python or sys.executable
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "blender"
    path.write_text(
        "#!/bin/sh\n"
        "# Test stand-in for blender: the bpy module behind Blender's command line (devkit/blender_cli.py).\n"
        f'PYTHONPATH={shlex.quote(str(ROOT))}"${{PYTHONPATH:+:$PYTHONPATH}}" '
        f'PYTHONUNBUFFERED=1 exec {shlex.quote(python)} -X faulthandler -m devkit.blender_cli "$@"\n'
    )
    path.chmod(0o755)
    return path


if __name__ == "__main__":
    # Leaves through hard_exit: bpy 4.5 as a module can hang in its own exit after GPU work.
    run(main)
