"""Repeated calls do not grow the process: 1,000 calls of each kind, RSS
(resident pages from /proc/self/statm) before and after, after a warm-up of
50 calls that lets allocators and caches reach their steady size.

Bound: 4 MiB of growth over 1,000 calls, i.e. 4 KiB a call. A leak of one
particle-force array per call (2000 x 3 doubles, 47 KiB) would grow the
process by 46 MiB; of one field view's owner (the stage grid, 7056 nodes x 24
bytes) by 160 MiB.
"""
import gc
import os

import numpy as np

import lodestone
from conftest import ball_particles, stage_grid, stage_sources

BOUND_BYTES = 4 * 1024 * 1024
PAGE = os.sysconf("SC_PAGE_SIZE")


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
    x, n = ball_particles()
    x32 = x.astype(np.float32)  # the converting path too
    sources = stage_sources()
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())

    def call():
        stage.run(x32, n, sources)
        stage.particle_forces(x32, n)
        stage.sample_field(x[::2])
        _ = stage.field, stage.nodal_force, stage.density
        sources.field(x)

    grown = growth(call)
    print(f"stage: RSS grew {grown / 1024:.0f} KiB over 1000 calls")
    assert grown < BOUND_BYTES


def test_fresh_stages_and_errors_do_not_grow_the_process():
    x, n = ball_particles(200)
    sources = stage_sources()

    def call():
        stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
        stage.run(x, n, sources)
        try:
            stage.run(x[:, :2], n, sources)
        except ValueError:
            pass
        try:
            stage.particle_forces(x[:10], n[:10])
        except ValueError:
            pass

    grown = growth(call)
    print(f"fresh stages: RSS grew {grown / 1024:.0f} KiB over 1000 calls")
    assert grown < BOUND_BYTES
