"""Atomic output: complete files only, with the permissions a user expects."""

from __future__ import annotations

import os
import stat

import pytest

from shadowgeo.io.atomic import atomic_path


def mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def test_new_file_gets_the_umask_mode_not_a_private_one(tmp_path):
    old = os.umask(0o022)
    try:
        with atomic_path(tmp_path / "out.x3d") as temporary:
            temporary.write_text("<X3D/>")
    finally:
        os.umask(old)
    assert mode(tmp_path / "out.x3d") == 0o644


def test_replaced_file_keeps_its_mode(tmp_path):
    target = tmp_path / "out.glb"
    target.write_bytes(b"old")
    os.chmod(target, 0o640)
    with atomic_path(target) as temporary:
        temporary.write_bytes(b"new")
    assert target.read_bytes() == b"new" and mode(target) == 0o640


def test_failure_leaves_the_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "out.usda"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_path(target) as temporary:
        temporary.write_text("half")
        raise RuntimeError("writer failed")
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.usda"]
