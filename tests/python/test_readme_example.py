"""The README's example script (section "fpp from Python", its first python
block) run as written, so that it stays true: headless (matplotlib's Agg
backend, no display, so the script leaves Open3D's viewer out) in a fresh
folder holding a capture made by fpp-calib simulate as pose-01 and its rig's
true table as table.fpt; the files it writes checked."""

import os
import re
import subprocess
import sys

import numpy as np
import pytest

import fpp
from conftest import SOURCE


def readme_example():
    with open(os.path.join(SOURCE, "README.md"), encoding="utf-8") as f:
        text = f.read()
    section = re.search(r"^## fpp from Python\n(.*?)^## ", text, re.S | re.M)
    assert section, "README.md has no section 'fpp from Python'"
    block = re.search(r"^```python\n(.*?)^```", section.group(1), re.S | re.M)
    assert block, "the section 'fpp from Python' has no python block"
    return block.group(1)


def test_the_readme_example_runs_and_writes_what_it_says(tmp_root, sim_capture, truth_table):
    pytest.importorskip("matplotlib", reason="python3-matplotlib (install-deps.sh tests)")
    script = readme_example()
    assert 'read_capture("pose-01")' in script and 'Table.load("table.fpt")' in script
    work = os.path.join(tmp_root, "readme-example")
    os.makedirs(work)
    os.symlink(sim_capture, os.path.join(work, "pose-01"))
    os.symlink(truth_table, os.path.join(work, "table.fpt"))
    with open(os.path.join(work, "example.py"), "w", encoding="utf-8") as f:
        f.write(script)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["MPLBACKEND"] = "Agg"
    env["MPLCONFIGDIR"] = os.path.join(work, "mpl")
    r = subprocess.run([sys.executable, "example.py"], cwd=work, env=env, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr

    # The same work here: the figures the script prints and the points it writes.
    result = fpp.decode(fpp.read_capture(sim_capture))
    xyz = fpp.Table.load(truth_table).apply(result.proj_x)
    expected = int(np.isfinite(xyz).all(axis=-1).sum())
    assert expected > 0.5 * xyz.shape[0] * xyz.shape[1]
    assert f"{result.coverage_of_lit:.1%} of the lit pixels decoded" in r.stdout
    assert f"{expected} points written" in r.stdout

    with open(os.path.join(work, "depth.png"), "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    import matplotlib.image
    png = matplotlib.image.imread(os.path.join(work, "depth.png"))
    assert png.ndim == 3 and png.shape[0] >= 100 and png.shape[1] >= 100
    assert np.ptp(png[..., :3]) > 0.5  # a drawn depth map, not a blank canvas

    cloud = fpp.read_ply(os.path.join(work, "scan.ply"))
    assert cloud.xyz.shape == xyz.shape
    assert cloud.count_points() == expected
    assert np.array_equal(cloud.xyz, xyz, equal_nan=True)
