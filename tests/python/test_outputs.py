"""The Python writers' output guarantees: folders and dangling links refused, atomic replacement (a write
that fails leaves the old file and no temporary file), never a half-written file."""

from __future__ import annotations

import os
import re
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import bsv


def test_folders_and_links_are_not_outputs(tmp_path: Path) -> None:
    pts = np.zeros((3, 3))
    with pytest.raises(bsv.OutputExistsError, match="is a folder"):
        bsv.write_point_cloud(tmp_path, pts, overwrite=True)
    link = tmp_path / "link.ply"
    link.symlink_to(tmp_path / "target.ply")
    with pytest.raises(bsv.OutputExistsError, match="already exists"):
        bsv.write_point_cloud(link, pts)
    assert not (tmp_path / "target.ply").exists()


@pytest.mark.skipif(not hasattr(resource, "RLIMIT_FSIZE"), reason="needs RLIMIT_FSIZE (POSIX)")
def test_a_file_size_limit_keeps_the_old_file_whole(tmp_path: Path) -> None:
    out = tmp_path / "c.ply"
    bsv.write_point_cloud(out, np.zeros((10, 3)))
    before = out.read_bytes()
    # A child process under a 64 KiB file-size limit replaces it with a 1.2 MB cloud: the write fails.
    code = (
        "import resource, numpy as np, bsv\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (65536, 65536))\n"
        f"bsv.write_point_cloud({str(out)!r}, np.zeros((50000, 3)), overwrite=True)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=dict(os.environ))
    assert r.returncode == 1, r.stderr
    assert "WriteError" in r.stderr and "c.ply" in r.stderr, r.stderr
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.ply"]


@pytest.mark.parametrize(("colors", "message"), [
    (np.full((3, 3), 300), "colors[0, 0] = 300 is outside 0..=255"),
    (np.full((3, 3), -1), "colors[0, 0] = -1 is outside 0..=255"),
    (np.full((3, 3), 0.5), "uint8 array, got float64"),
])
def test_colours_out_of_range_are_refused_not_wrapped(tmp_path: Path, colors: np.ndarray, message: str) -> None:
    with pytest.raises(bsv.InputError, match=re.escape(message)):
        bsv.write_point_cloud(tmp_path / "c.ply", np.zeros((3, 3)), colors=colors)
    assert not (tmp_path / "c.ply").exists()
    bsv.write_point_cloud(tmp_path / "ok.ply", np.zeros((3, 3)), colors=np.full((3, 3), 255, dtype=np.int64))
    c = bsv.read_point_cloud(tmp_path / "ok.ply")
    assert c.colors is not None and c.colors.tolist() == [[255, 255, 255]] * 3
