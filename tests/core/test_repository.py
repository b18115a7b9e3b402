"""The repository stands on its own: nothing in it reads or names a folder beside the checkout,
techniques are cited by their published sources, and the README stays a user's page."""

import re
import subprocess

from devkit.session import ROOT

OUTSIDE = re.compile(r"\.\./shared|shared/assets|seeds?/")
DOCUMENT_NUMBER = re.compile(r"\bseeds? ?\d{3}\b", re.IGNORECASE)


def _tracked_names():
    """``git ls-files``; outside a checkout (the GPU bundle holds ``git archive HEAD``, the
    tracked files without git), every file but Python's caches."""
    if (ROOT / ".git").exists():
        return subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    return [p.relative_to(ROOT).as_posix() for p in ROOT.rglob("*") if p.is_file() and "__pycache__" not in p.parts]


def _tracked_text_files():
    names = _tracked_names()
    for name in names:
        path = ROOT / name
        if path.suffix in {".npz", ".png", ".exr", ".blend", ".zip"} or not path.is_file():
            continue
        try:
            yield name, path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue


def test_nothing_reads_or_names_a_folder_beside_the_repository():
    this = f"tests/core/{__name__.rsplit('.', 1)[-1]}.py"
    found = [
        f"{name}:{n}"
        for name, text in _tracked_text_files()
        if name != this
        for n, line in enumerate(text.splitlines(), 1)
        if OUTSIDE.search(line) or DOCUMENT_NUMBER.search(line)
    ]
    assert not found, found


def test_the_readme_is_a_users_page():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 310
    for doc in ("docs/benchmarks.md", "docs/design.md", "docs/materials.md", "devkit/meshes/README.md"):
        assert (ROOT / doc).is_file(), doc
