"""Bad inputs raise Python exceptions carrying the C++ message.

reference.cpp --errors makes the same bad calls through the C++ API and
prints each message; every Python call here must raise ValueError (the
mapping of lodestone::InvalidArgument) with exactly that message.
"""
import math
import os
import subprocess

import numpy as np
import pytest

import lodestone
from conftest import stage_grid


def stage():
    return lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())


def out_of_grid():
    stage().run([[0, 0, 0], [0.5, 0, 0]], [1e15, 1e15], lodestone.UniformField((0, 0, 1e4)))


def non_finite():
    stage().run([[0, math.nan, 0]], [1e15], lodestone.UniformField((0, 0, 1e4)))


def other_particles():
    s = stage()
    x = np.array([[0, 0, 0], [0.001, 0, 0]], dtype=float)
    s.run(x, [1e15, 1e15], lodestone.UniformField((0, 0, 1e4)))
    s.particle_forces(x[:1], [1e15])


def bad_tolerance():
    settings = lodestone.StageSettings()
    settings.tolerance = -1
    lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material(), settings)


def small_mpm_grid():
    lodestone.MpmSolver(lodestone.MpmSettings(lodestone.Grid((0, 0, 0), 0.01, (3, 8, 8))))


CASES = [
    lambda: lodestone.Grid((0, 0, 0), -1.0, (3, 3, 3)),
    lambda: lodestone.langevin_material(-1.0, 300.0, 1e23),
    lambda: lodestone.linear_material(-0.5, 1e23),
    lambda: lodestone.TimeProfile.ramp(1.0, 0.0),
    lambda: lodestone.SphereMagnet(lodestone.Pose(), -0.01, (0, 0, 1e5)),
    lambda: lodestone.CylinderMagnet(lodestone.Pose(), 0.01, 0.01, (1e5, 0, 1e5)),
    lambda: lodestone.Pose.from_quaternion((0, 0, 0), 0, 0, 0, 0),
    out_of_grid,
    non_finite,
    other_particles,
    bad_tolerance,
    lambda: lodestone.neo_hookean_solid(2e5, 0.6, 1000.0),
    small_mpm_grid,
    lambda: lodestone.Scene.parse('{"name": "s", "domian": {}}', "bad.json"),
    lambda: lodestone.node_type("magnetic_forse"),
]


def cpp_messages():
    out = subprocess.run([os.environ["LODESTONE_REFERENCE"], "--errors"], check=True, capture_output=True, text=True)
    return out.stdout.split("\n---\n")[:-1]


def test_every_bad_input_raises_value_error_with_the_cpp_message():
    expected = cpp_messages()
    assert len(expected) == len(CASES)
    for case, message in zip(CASES, expected):
        assert message != "(no error)"
        with pytest.raises(ValueError) as e:
            case()
        assert str(e.value) == message


def test_python_level_argument_errors_name_the_argument():
    with pytest.raises(ValueError, match=r"H: expected 3 numbers \(shape \(3,\)\), got shape \(2,\)"):
        lodestone.UniformField((1.0, 2.0))
    with pytest.raises(ValueError, match="boundary: expected 'open' or 'shield', got 'closed'"):
        lodestone.StageSettings().boundary = "closed"
    with pytest.raises(ValueError, match="rotation: expected a 3 x 3 matrix"):
        lodestone.Pose((0, 0, 0), np.eye(2))
    with pytest.raises(ValueError, match="shape: expected 'plane', 'box', 'sphere' or 'cylinder', got 'cone'"):
        lodestone.Collider("cone")


def test_network_errors_name_the_path():
    with pytest.raises(ValueError, match=r"network: nodes\[0\]\.type"):
        lodestone.Network.from_dict({"nodes": [{"name": "a", "type": "magnetic_forse"}], "connections": []})
    net = lodestone.Network()
    net.add_node("magnet", "m")
    with pytest.raises(ValueError, match="set_params"):
        net.set_params("m", {"radiuss": 0.1})


def test_cook_failure_is_a_cook_error():
    assert issubclass(lodestone.CookError, RuntimeError)
    assert issubclass(lodestone.NotBuiltError, RuntimeError)
