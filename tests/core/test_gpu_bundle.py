"""The GPU bundle's scripts (tools/gpu_bundle.sh packs, tools/gpu_bundle_run.sh checks, unpacks
and runs): the runner names a missing or a corrupt part and stops, unpacks intact parts, and the
packer's list of left-out GPU kernels matches files of the installed bpy."""

import io
import lzma
import os
import shutil
import subprocess
import tarfile

import pytest

from devkit.session import ROOT

PACKER = ROOT / "tools" / "gpu_bundle.sh"
RUNNER = ROOT / "tools" / "gpu_bundle_run.sh"
NAME = "penumbra-gpu"
VENV_SITE = ROOT / ".venv" / "blender-5.2" / "lib" / "python3.13" / "site-packages"


def _run(*args, **kwargs):
    return subprocess.run(["bash", *map(str, args)], capture_output=True, text=True, timeout=60, **kwargs)


@pytest.mark.parametrize("script", [PACKER, RUNNER], ids=lambda p: p.name)
def test_the_scripts_parse(script):
    proc = _run("-n", script)
    assert proc.returncode == 0, proc.stderr
    assert "set -euo pipefail" in script.read_text()


@pytest.fixture
def fake_bundle(tmp_path):
    """Parts of a tiny bundle (an archive of ``penumbra-gpu/``, 4 parts of 1 KiB or less) with
    SHA256SUMS and the runner beside them, laid out as tools/gpu_bundle.sh lays them out."""
    payload = os.urandom(3500)  # incompressible: the archive spans several parts
    data = io.BytesIO()
    with lzma.open(data, "wb") as xz, tarfile.open(fileobj=xz, mode="w") as tar:
        for name, content, mode in (
            ("python/bin/python3.13", b"#!/bin/sh\n", 0o755),
            ("repo/payload.bin", payload, 0o644),
        ):
            info = tarfile.TarInfo(f"{NAME}/{name}")
            info.size, info.mode = len(content), mode
            tar.addfile(info, io.BytesIO(content))
    parts = tmp_path / "parts"
    parts.mkdir()
    archive = parts / f"{NAME}.tar.xz"
    archive.write_bytes(data.getvalue())
    subprocess.run(["split", "-b", "1k", "-d", "-a", "2", archive.name, f"{archive.name}.part-"], cwd=parts, check=True)
    names = sorted(p.name for p in parts.glob(f"{NAME}.tar.xz.part-*")) + [archive.name]
    sums = subprocess.run(["sha256sum", *names], cwd=parts, check=True, capture_output=True, text=True).stdout
    (parts / "SHA256SUMS").write_text(sums)
    archive.unlink()
    shutil.copy(RUNNER, parts / RUNNER.name)
    assert len(list(parts.glob(f"{NAME}.tar.xz.part-*"))) == 4
    return parts, payload


def test_intact_parts_are_checked_and_unpacked_anywhere(fake_bundle, tmp_path):
    parts, payload = fake_bundle
    proc = _run(parts / RUNNER.name, "--check")
    assert proc.returncode == 0, proc.stderr
    assert "all 4 parts present and intact" in proc.stdout
    dest = tmp_path / "elsewhere" / "unpacked"
    proc = _run(parts / RUNNER.name, "--unpack-only", "--dest", dest)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "unpacked into" in proc.stdout
    assert (dest / NAME / "repo" / "payload.bin").read_bytes() == payload
    # Unpacked once, the bundle there is reused: its parts may be gone.
    for part in parts.glob(f"{NAME}.tar.xz.part-*"):
        part.unlink()
    proc = _run(parts / RUNNER.name, "--unpack-only", "--dest", dest)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "reusing the bundle" in proc.stdout


def test_a_missing_part_is_named(fake_bundle, tmp_path):
    parts, _ = fake_bundle
    (parts / f"{NAME}.tar.xz.part-01").unlink()
    for args in (["--check"], ["--unpack-only", "--dest", tmp_path / "dest"]):
        proc = _run(parts / RUNNER.name, *args)
        assert proc.returncode == 3, proc.stdout + proc.stderr
        assert f"MISSING part {NAME}.tar.xz.part-01" in proc.stderr
        assert "part-00" not in proc.stderr and "CORRUPT" not in proc.stderr
    assert not (tmp_path / "dest" / NAME).exists()


def test_a_corrupt_part_is_named(fake_bundle, tmp_path):
    parts, _ = fake_bundle
    part = parts / f"{NAME}.tar.xz.part-02"
    data = bytearray(part.read_bytes())
    data[100] ^= 0x01
    part.write_bytes(bytes(data))
    for args in (["--check"], ["--unpack-only", "--dest", tmp_path / "dest"]):
        proc = _run(parts / RUNNER.name, *args)
        assert proc.returncode == 3, proc.stdout + proc.stderr
        assert f"CORRUPT part {NAME}.tar.xz.part-02" in proc.stderr
        assert "part-01" not in proc.stderr and "MISSING" not in proc.stderr
    assert not (tmp_path / "dest" / NAME).exists()


def test_no_checksum_file_is_an_error(fake_bundle):
    parts, _ = fake_bundle
    (parts / "SHA256SUMS").unlink()
    proc = _run(parts / RUNNER.name, "--check")
    assert proc.returncode == 3
    assert "no SHA256SUMS" in proc.stderr


@pytest.mark.skipif(not (VENV_SITE / "bpy").is_dir(), reason="no .venv/blender-5.2 (tools/setup.sh 5.2)")
def test_the_left_out_kernels_are_files_of_the_installed_bpy():
    proc = _run(PACKER, "--list-excludes", cwd=ROOT)
    assert proc.returncode == 0, proc.stderr  # every pattern matches at least one file
    listed = [line.split("\t")[1] for line in proc.stdout.splitlines()]
    assert all((VENV_SITE / name).is_file() for name in listed)
    assert all(name.startswith("bpy/") for name in listed)
    dropped = sum((VENV_SITE / name).stat().st_size for name in listed)
    assert dropped > 50 * 2**20, dropped
    kinds = {name.rsplit(".", 2)[-2] for name in listed if name.endswith(".zst")}
    assert {"fatbin", "hipfb"} <= kinds, kinds
    # What bpy links must stay loadable: only the oneAPI library, which the packer stubs.
    if shutil.which("readelf"):
        dynamic = subprocess.run(
            ["readelf", "-d", VENV_SITE / "bpy" / "__init__.so"], capture_output=True, text=True, check=True
        ).stdout
        needed = {line.split("[")[1].rstrip("]") for line in dynamic.splitlines() if "(NEEDED)" in line}
        linked = {name.rsplit("/", 1)[1] for name in listed} & needed
        assert linked == {"libcycles_kernel_oneapi_aot.so"}, linked
