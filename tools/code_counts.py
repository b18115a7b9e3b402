"""List the engine's functions that are long or take many parameters, the measures of issue 49's
"long functions split where their subjects change".

    python -m tools.code_counts                  # engine/, over 100 lines or over 8 parameters
    python -m tools.code_counts --lines 60 engine/shadows
    python -m tools.code_counts --techniques     # the files of engine/ and shaders/ naming each technique

A function's lines run from its first decorator to its last line (docstring included); its
parameters are every kind Python has (positional-only, ordinary, keyword-only, ``*args``,
``**kwargs``) less ``self`` and ``cls``. The engine's Blender-facing API (``API``) is listed
apart: its signatures are what devkit, the tests and the render loop call. Read with ``ast``
alone, so it needs no Blender."""

import argparse
import ast
import io
import pathlib
import re
import sys
import tokenize

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


# The frame's techniques (engine/frame/features/) and the names that mark them, as issue 49
# counted them (``git grep -il``).
TECHNIQUES = {
    "world ratio": "world_ratio",
    "settling": "settle",
    "bounce": "rsm|bounce",
    "world occlusion": "world_ao|gtao",
}


def _python_code(text):
    """``text`` (Python) without its comments and docstrings."""
    tree = ast.parse(text)
    lines = text.splitlines(keepends=True)
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr):
            value = body[0].value
            if isinstance(value, ast.Constant) and isinstance(value.value, str):
                for i in range(body[0].lineno - 1, body[0].end_lineno):
                    lines[i] = "\n"
    out = []
    for tok in tokenize.generate_tokens(io.StringIO("".join(lines)).readline):
        if tok.type != tokenize.COMMENT:
            out.append(tok.string)
    return " ".join(out)


def _glsl_code(text):
    """``text`` (GLSL) without its comments."""
    return re.sub(r"//[^\n]*", "", re.sub(r"/\*.*?\*/", "", text, flags=re.S))


def technique_files(roots=("engine", "shaders")):
    """{technique: (files naming it anywhere, files naming it in code)} over ``roots``."""
    files = [p for r in roots for p in sorted((ROOT / r).rglob("*")) if p.suffix in (".py", ".glsl")]
    out = {}
    for name, pattern in TECHNIQUES.items():
        rx = re.compile(pattern, re.I)
        anywhere, code = [], []
        for path in files:
            text = path.read_text(encoding="utf-8")
            if not rx.search(text):
                continue
            rel = path.relative_to(ROOT).as_posix()
            anywhere.append(rel)
            if rx.search(_python_code(text) if path.suffix == ".py" else _glsl_code(text)):
                code.append(rel)
        out[name] = (anywhere, code)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="*", default=[str(ROOT / "engine")], help="files or folders to read")
    parser.add_argument("--lines", type=int, default=100, help="report functions over this many lines")
    parser.add_argument("--params", type=int, default=8, help="report functions with more parameters than this")
    parser.add_argument("--techniques", action="store_true", help="count the files naming each technique")
    args = parser.parse_args(argv)
    if args.techniques:
        for name, (anywhere, code) in technique_files().items():
            print(f"{name} ({TECHNIQUES[name]}): {len(anywhere)} files, {len(code)} in code")
            print("  " + " ".join(code))
        return 0
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
