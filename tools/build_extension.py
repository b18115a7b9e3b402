"""Build the Penumbra extension zip with Blender's own extension tool (``devkit.extension``).

.venv/blender-5.2/bin/python -m tools.build_extension --out out
"""

import argparse
import sys
from pathlib import Path

from devkit import session
from devkit.extension import BuildError, build_zip


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, type=Path, help="output folder for the zip (created if missing)")
    parser.add_argument(
        "--source", default=session.ROOT, type=Path, help="extension source folder (default: the repository root)"
    )
    args = parser.parse_args(argv)
    try:
        zip_path = build_zip(args.out, args.source)
    except BuildError as exc:
        print(f"build_extension: error: {exc}", file=sys.stderr)
        return 1
    print(zip_path)
    return 0


if __name__ == "__main__":
    session.run(main)
