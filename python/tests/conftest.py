"""Shared set-ups of the lodestone module's tests.

The stage set-up (grid, sources, material, ball of particles) is mirrored
by reference.cpp, the C++ program test_reference.py compares against.
"""
import os
import pathlib

import numpy as np
import pytest

import lodestone

SOURCE_DIR = pathlib.Path(os.environ.get("LODESTONE_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
BINARY_DIR = pathlib.Path(os.environ.get("LODESTONE_BINARY_DIR", SOURCE_DIR / "build"))


def stage_grid():
    """The reference stage grid: 21 x 21 x 16 nodes of 4 mm."""
    return lodestone.Grid((-0.04, -0.04, -0.02), 0.004, (21, 21, 16))


def stage_sources():
    """A box magnet below the ball (M = 8e5 A/m along z) plus a uniform 1e4 A/m along z."""
    return lodestone.FieldSourceSet([
        lodestone.CuboidMagnet(lodestone.Pose((0.0, 0.0, -0.035)), (0.01, 0.01, 0.005), (0.0, 0.0, 8e5)),
        lodestone.UniformField((0.0, 0.0, 1e4)),
    ])


def ball_particles(count=2000, seed=3):
    """`count` points uniform in a ball of radius 12 mm at (0, 0, 10) mm, carrying the paper's n0 times
    the ball's volume in total (positions m, counts micro-particles)."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(count, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    r = 0.012 * rng.uniform(size=count) ** (1.0 / 3.0)
    x = d * r[:, None] + np.array([0.0, 0.0, 0.01])
    n0 = lodestone.paper_material().number_density
    counts = np.full(count, n0 * (4.0 / 3.0) * np.pi * 0.012 ** 3 / count)
    return np.ascontiguousarray(x), counts


@pytest.fixture
def stage_run():
    """A stage that has run on the reference ball: (stage, positions, counts, sources)."""
    x, n = ball_particles()
    sources = stage_sources()
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
    report = stage.run(x, n, sources)
    assert report.converged
    return stage, x, n, sources


def bits(a):
    """The array's bytes as uint64 words, for bit-for-bit comparisons."""
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)
