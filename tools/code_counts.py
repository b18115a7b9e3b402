"""List the engine's functions that are long or take many parameters, the measures of issue 49's
"long functions split where their subjects change".

    python -m tools.code_counts                  # engine/, over 100 lines or over 8 parameters
    python -m tools.code_counts --lines 60 engine/shadows

A function's lines run from its first decorator to its last line (docstring included); its
parameters are every kind Python has (positional-only, ordinary, keyword-only, ``*args``,
``**kwargs``) less ``self`` and ``cls``. The engine's Blender-facing API (``API``) is listed
apart: its signatures are what devkit, the tests and the render loop call. Read with ``ast``
alone, so it needs no Blender."""

import argparse
import ast
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent

# (file under the repository root, qualified name) of functions exempt as Blender-facing API
API = {("engine/render_engine.py", "PenumbraEngineCore.render_frame")}


def _params(node):
    args = node.args
    names = [a.arg for a in args.posonlyargs + args.args + args.kwonlyargs]
    names += [a.arg for a in (args.vararg, args.kwarg) if a is not None]
    return [n for n in names if n not in ("self", "cls")]


def _functions(tree):
    """(qualified name, node) of every function in ``tree``, methods and nested ones by dotted path."""
    stack = [("", tree)]
    while stack:
        prefix, parent = stack.pop()
        for node in ast.iter_child_nodes(parent):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                name = prefix + node.name
                if not isinstance(node, ast.ClassDef):
                    yield name, node
                stack.append((name + ".", node))


def measure(paths):
    """(path, qualified name, lines, parameters) of every function in the .py files under ``paths``."""
    rows = []
    for top in paths:
        top = pathlib.Path(top)
        for path in sorted(top.rglob("*.py")) if top.is_dir() else [top]:
            tree = ast.parse(path.read_text(), filename=str(path))
            for name, node in _functions(tree):
                first = min([node.lineno] + [d.lineno for d in node.decorator_list])
                rows.append((path, name, node.end_lineno - first + 1, len(_params(node))))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="*", default=[str(ROOT / "engine")], help="files or folders to read")
    parser.add_argument("--lines", type=int, default=100, help="report functions over this many lines")
    parser.add_argument("--params", type=int, default=8, help="report functions with more parameters than this")
    args = parser.parse_args(argv)
    rows = measure(args.paths)

    def where(path):
        try:
            return path.resolve().relative_to(ROOT).as_posix()
        except ValueError:
            return str(path)

    def show(path, name, value, unit):
        print(f"  {value:4d} {unit}  {where(path)}:{name}")

    exempt = [r for r in rows if (where(r[0]), r[1]) in API and (r[2] > args.lines or r[3] > args.params)]
    rows = [r for r in rows if (where(r[0]), r[1]) not in API]
    long = sorted((r for r in rows if r[2] > args.lines), key=lambda r: -r[2])
    many = sorted((r for r in rows if r[3] > args.params), key=lambda r: -r[3])
    print(f"over {args.lines} lines: {len(long)}")
    for path, name, lines, _ in long:
        show(path, name, lines, "lines")
    print(f"over {args.params} parameters: {len(many)}")
    for path, name, _, params in many:
        show(path, name, params, "params")
    for path, name, lines, params in exempt:
        print(f"exempt (API): {where(path)}:{name} ({lines} lines, {params} params)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
