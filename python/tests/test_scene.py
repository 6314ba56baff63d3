"""Scenes through Python: load, validate, run with frame callbacks; the MPM
solver's particle arrays; VDB export and import."""
import numpy as np
import pytest

import lodestone
from conftest import SOURCE_DIR


def cube_scene():
    return lodestone.Scene.load(str(SOURCE_DIR / "examples/scenes/cube_langevin.json"), dx=0.03)


def test_scene_run_equals_stepping_the_built_solver():
    scene = cube_scene()
    assert scene.name == "cube-langevin" and scene.fps == 500
    frames_seen = []
    solver, reports = scene.run(frames=2, on_frame=lambda f, s: frames_seen.append((f, s.time)))
    assert [r["frame"] for r in reports] == [1, 2] and [f for f, _ in frames_seen] == [1, 2]
    assert frames_seen[-1][1] == pytest.approx(2 / 500)
    # The same frames through build_solver and advance_frame: identical state.
    other = scene.build_solver()
    for _ in range(2):
        other.advance_frame(scene.frame_duration)
    np.testing.assert_array_equal(other.positions, solver.positions)
    np.testing.assert_array_equal(other.velocities, solver.velocities)
    # The cube falls toward the magnet below it and is pulled by it.
    assert reports[0]["field_solves"] >= 1
    assert reports[-1]["magnetic_impulse"][2] < 0


def test_particle_arrays_are_copies():
    solver = cube_scene().build_solver()
    x = solver.positions
    x[:] = 0.0
    assert np.abs(solver.positions).max() > 0
    assert solver.positions.shape == (solver.particle_count, 3)
    assert solver.ids.dtype == np.uint64 and len(np.unique(solver.ids)) == solver.particle_count
    assert solver.counts.sum() > 0


@pytest.mark.skipif(not lodestone.vdb_built(), reason="OpenVDB not built")
def test_vdb_round_trip(tmp_path):
    scene = cube_scene()
    solver, _ = scene.run(frames=1)
    lodestone.write_particles_vdb(str(tmp_path / "p.vdb"), solver, frame=1)
    back = lodestone.read_particles_vdb(str(tmp_path / "p.vdb"))
    order, back_order = np.argsort(solver.ids), np.argsort(back["ids"])
    np.testing.assert_array_equal(back["ids"][back_order], solver.ids[order])
    # Positions are stored as 16-bit offsets within voxels of dx: error <= dx / 65535.
    err = np.abs(back["positions"][back_order] - solver.positions[order]).max()
    assert err <= scene.grid.dx / 65535 * 1.01
    assert back["frame"] == 1

    from conftest import ball_particles, stage_grid, stage_sources
    x, n = ball_particles()
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
    stage.run(x, n, stage_sources())
    lodestone.write_fields_vdb(str(tmp_path / "f.vdb"), stage, frame=3, time=0.25, double_precision=True)
    H = lodestone.read_vdb_grid(str(tmp_path / "f.vdb"), "H", stage.grid, vector=True)
    np.testing.assert_array_equal(H, stage.field)
    n_back = lodestone.read_vdb_grid(str(tmp_path / "f.vdb"), "n", stage.grid)
    np.testing.assert_array_equal(n_back, stage.density)


def test_memory_estimate_counts_the_scene_by_part():
    scene = cube_scene()
    m = scene.memory_estimate()
    solver = scene.build_solver()
    grid = scene.grid
    # The counts are the scene's: the nodes of the MPM grid's box that the
    # particles' stencils reach (the grid holds memory there only), the
    # particles, and a field-solve grid padded around the whole domain (the
    # cube is magnetic, a magnet is there).
    u = (np.asarray(solver.positions) - np.asarray(grid.origin)) / grid.dx
    lo = np.maximum(np.floor(u.min(axis=0) - 0.5), 0)
    hi = np.minimum(np.floor(u.max(axis=0) - 0.5) + 3, grid.dims)
    assert m["mpm_nodes"] == np.prod(hi - lo)
    assert m["mpm_nodes"] < np.prod(grid.dims)
    assert m["particles"] == solver.particle_count
    assert m["field_solve_nodes"] > np.prod(grid.dims)
    # Each part is its count times the documented figure (docs/cli.md, "Memory").
    # The MPM grid's pages for those runs: 64 B a node (node data, velocity,
    # bin), with up to a page of each of its three arrays more on each row.
    rows = np.prod(hi - lo) / (hi - lo)[0]
    assert 60 * m["mpm_nodes"] < m["mpm_grid_bytes"] < 64 * m["mpm_nodes"] + 3 * 4096 * rows
    # The cube's material cells: its own and the two cells around them that
    # its points' deposit reaches, at most.
    cube_cells = np.prod(np.ptp(u, axis=0) + 1)
    assert cube_cells < m["field_material_cells"] < np.prod(np.ptp(u, axis=0) + 5)
    assert m["field_solve_bytes"] == 356 * m["field_solve_nodes"] + 1300 * m["field_material_cells"]
    assert m["particles_bytes"] == (392 + 150) * m["particles"]
    assert m["total_bytes"] == pytest.approx(
        m["mpm_grid_bytes"] + m["field_solve_bytes"] + m["particles_bytes"] + m["previews_bytes"])
    assert 0 < m["total_bytes"] < m["limit_bytes"]
