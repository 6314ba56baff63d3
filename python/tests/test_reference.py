"""The module's results equal the C++ API's bit for bit on the same inputs.

reference.cpp computes the stage run (particle forces, sampled H, nodal force,
potential, total force), the sources' applied field and one MPM substep with
the C++ API; this test computes the same through Python and compares the
float64 words.
"""
import os
import subprocess

import numpy as np

import lodestone
from conftest import ball_particles, bits, stage_grid, stage_sources


def reference(tmp_path, x, n):
    x.tofile(tmp_path / "x.f64")
    n.tofile(tmp_path / "n.f64")
    subprocess.run([os.environ["LODESTONE_REFERENCE"], str(tmp_path / "x.f64"), str(tmp_path / "n.f64"),
                    str(tmp_path)], check=True)
    return lambda name: np.fromfile(tmp_path / f"{name}.f64", dtype=np.float64)


def test_stage_and_fields_equal_cpp_bit_for_bit(tmp_path):
    x, n = ball_particles()
    cpp = reference(tmp_path, x, n)
    sources = stage_sources()
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
    report = stage.run(x, n, sources)
    assert report.converged
    forces = stage.particle_forces(x, n)
    assert np.abs(forces).max() > 0  # a real force, not zeros on both sides
    np.testing.assert_array_equal(bits(forces), bits(cpp("particle_forces").reshape(-1, 3)))
    np.testing.assert_array_equal(bits(stage.sample_field(x)), bits(cpp("sampled_field").reshape(-1, 3)))
    # Grid arrays are [i, j, k] views of x-fastest storage: Fortran order gives the C++ layout.
    np.testing.assert_array_equal(bits(stage.nodal_force.transpose(2, 1, 0, 3)), bits(cpp("nodal_force").reshape(16, 21, 21, 3)))
    np.testing.assert_array_equal(bits(stage.potential.ravel(order="F")), bits(cpp("potential")))
    np.testing.assert_array_equal(bits(report.total_force), bits(cpp("total_force")))
    np.testing.assert_array_equal(bits(sources.field(x)), bits(cpp("applied_field").reshape(-1, 3)))


def test_one_mpm_step_equals_cpp_bit_for_bit(tmp_path):
    x, n = ball_particles(50)
    cpp = reference(tmp_path, x, n)
    grid = lodestone.Grid((-0.04, -0.04, -0.04), 0.005, (17, 17, 17))
    settings = lodestone.MpmSettings(grid)
    settings.fixed_dt = 1e-4
    solver = lodestone.MpmSolver(settings)
    material = solver.add_material(lodestone.neo_hookean_solid(2e5, 0.3, 1000.0, lodestone.paper_material()))
    solver.emit(lodestone.Shape.box(lodestone.Pose((0.0, 0.0, 0.0)), (0.01, 0.01, 0.01)), material)
    solver.add_magnet(lodestone.CuboidMagnet(lodestone.Pose((0.0, 0.0, -0.025)), (0.01, 0.01, 0.004), (0.0, 0.0, 8e5)),
                      boundary="sticky")
    report = solver.step(1e-4)
    assert report["magnetic_solved"]
    assert np.abs(report["magnetic_impulse"]).max() > 0
    np.testing.assert_array_equal(bits(solver.positions), bits(cpp("mpm_x").reshape(-1, 3)))
    np.testing.assert_array_equal(bits(solver.velocities), bits(cpp("mpm_v").reshape(-1, 3)))
