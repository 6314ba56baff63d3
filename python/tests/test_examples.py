"""The examples run: the wedge writes a PNG and a CSV whose forces grow with
the magnet's strength (the linear material faster than the saturating
Langevin one); the Blender script simulates a scene outside Blender and its
particle files read back."""
import csv
import subprocess
import sys

import numpy as np
import pytest

import lodestone
from conftest import SOURCE_DIR


def test_wedge_example_writes_png_and_csv(tmp_path):
    png = tmp_path / "wedge.png"
    subprocess.run([sys.executable, str(SOURCE_DIR / "python/examples/wedge_magnet_strength.py"), "--out", str(png),
                    "--steps", "3"], check=True)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rows = list(csv.DictReader(open(tmp_path / "wedge.csv")))
    assert len(rows) == 3
    langevin = np.array([float(r["force_z_langevin_N"]) for r in rows])
    linear = np.array([float(r["force_z_linear_N"]) for r in rows])
    assert np.all(np.diff(-langevin) > 0) and np.all(np.diff(-linear) > 0)
    # Saturation: the Langevin pull grows slower than the linearized one over the wedge.
    assert linear[-1] / linear[0] > langevin[-1] / langevin[0]


@pytest.mark.skipif(not lodestone.vdb_built(), reason="OpenVDB not built")
def test_blender_script_simulates_outside_blender(tmp_path):
    sys.path.insert(0, str(SOURCE_DIR / "python/examples"))
    try:
        import blender_run_scene
    finally:
        sys.path.pop(0)
    written = blender_run_scene.simulate(str(SOURCE_DIR / "examples/scenes/cube_langevin.json"), str(tmp_path),
                                         frames=2, dx=0.03)
    assert [f for f, _ in written] == [1, 2]
    data = lodestone.read_particles_vdb(written[-1][1])
    assert len(data["positions"]) > 100 and data["frame"] == 2
