"""Repeated calls do not grow the process: 1,000 calls of each kind, RSS
(resident pages from /proc/self/statm) before and after, after a warm-up of
50 calls that lets allocators and caches reach their steady size.

Bound: 4 MiB of growth over 1,000 calls, i.e. 4 KiB a call. A leak of one
particle-force array per call (400 x 3 doubles, 9.4 KiB) would grow the
process by 9 MiB; of a stage (its grids, 1452 nodes) by far more.
"""
import gc
import os

import numpy as np

import lodestone
from conftest import ball_particles, stage_grid, stage_sources

BOUND_BYTES = 4 * 1024 * 1024
PAGE = os.sysconf("SC_PAGE_SIZE")


def small_grid():
    """11 x 11 x 12 nodes of 4 mm around the reference ball: cheap runs."""
    return lodestone.Grid((-0.02, -0.02, -0.012), 0.004, (11, 11, 12))


def rss():
    gc.collect()
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * PAGE


def growth(call, calls=1000, warmup=50):
    for _ in range(warmup):
        call()
    before = rss()
    for _ in range(calls):
        call()
    return rss() - before


def test_stage_runs_and_outputs_do_not_grow_the_process():
    x, n = ball_particles(400)
    x32 = x.astype(np.float32)  # the converting path too
    sources = stage_sources()
    stage = lodestone.MagneticForceStage(small_grid(), lodestone.paper_material())

    def call():
        stage.run(x32, n, sources)
        stage.particle_forces(x32, n)
        stage.sample_field(x[::2])
        _ = stage.field, stage.nodal_force, stage.density
        sources.field(x)

    grown = growth(call)
    print(f"stage: RSS grew {grown / 1024:.0f} KiB over 1000 calls")
    assert grown < BOUND_BYTES
