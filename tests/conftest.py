"""Test harness: loads the repository as the ``penumbra`` package inside the bpy module and
offers helpers to render and read back images. Tests use real Blender and the real gpu module
(Mesa llvmpipe via EGL); nothing is mocked."""

import importlib.util
import os
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "tests"))


def load_penumbra():
    """Import the repository root as the package ``penumbra`` (its folder name may differ)."""
    if "penumbra" in sys.modules:
        return sys.modules["penumbra"]
    spec = importlib.util.spec_from_file_location(
        "penumbra", ROOT / "__init__.py", submodule_search_locations=[str(ROOT)]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules["penumbra"] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def penumbra():
    module = load_penumbra()
    module.register()
    yield module
    module.unregister()


@pytest.fixture
def tmp(tmp_path):
    return tmp_path
