"""Field sources, poses, time profiles and laws through Python, checked
against closed forms."""
import math

import numpy as np
import pytest

import lodestone


def dipole(m, r):
    d = np.linalg.norm(r, axis=-1, keepdims=True)
    u = r / d
    return (3 * np.sum(u * m, axis=-1, keepdims=True) * u - m) / (4 * math.pi * d ** 3)


def test_sphere_magnet_outside_is_the_dipole_of_its_moment():
    M, R = np.array([0.0, 0.0, 8e5]), 0.01
    pose = lodestone.Pose.from_axis_angle((0.01, 0.02, 0.0), (1.0, 0.0, 0.0), 0.3)
    sphere = lodestone.SphereMagnet(pose, R, M)
    rng = np.random.default_rng(2)
    x = rng.uniform(-0.1, 0.1, (200, 3))
    x = x[np.linalg.norm(x - pose.position, axis=1) > 1.2 * R]
    moment = sphere.moment()
    np.testing.assert_allclose(moment, pose.rotation @ M * (4 / 3 * math.pi * R ** 3), rtol=1e-14)
    np.testing.assert_allclose(sphere.field(x), dipole(moment, x - pose.position), rtol=1e-10, atol=1e-9)
    # Inside: the magnetization, rotated to the world frame; the field is -M/3.
    np.testing.assert_allclose(sphere.magnetization(pose.position), pose.rotation @ M, rtol=1e-14)
    np.testing.assert_allclose(sphere.field(pose.position), -pose.rotation @ M / 3, rtol=1e-12)


def test_point_dipole_uniform_field_and_set():
    m = np.array([0.1, -0.2, 0.3])
    d = lodestone.PointDipole((0.0, 0.0, 0.0), m, lodestone.TimeProfile.constant(2.0))
    u = lodestone.UniformField((1.0, 2.0, 3.0), lodestone.TimeProfile.ramp(0.0, 1.0))
    x = np.array([[0.1, 0.0, 0.0], [0.0, 0.2, 0.1], [0.3, -0.1, 0.05]])
    np.testing.assert_allclose(d.field(x), dipole(2 * m, x), rtol=1e-13)
    np.testing.assert_allclose(u.field(x, 0.25), np.tile([0.25, 0.5, 0.75], (3, 1)), rtol=1e-15)
    both = lodestone.FieldSourceSet([d, u])
    assert len(both) == 2 and u.is_uniform and not both.is_uniform
    np.testing.assert_allclose(both.field(x, 0.5), d.field(x, 0.5) + u.field(x, 0.5), rtol=1e-15)
    # One point gives shape (3,) and the same bits as the batch.
    single = both.field(x[1], 0.5)
    assert single.shape == (3,)
    np.testing.assert_array_equal(single, both.field(x, 0.5)[1])
    # float32 positions are converted.
    np.testing.assert_array_equal(d.field(x.astype(np.float32)), d.field(x.astype(np.float32).astype(np.float64)))


def test_moving_a_magnet_and_a_magnet_in_a_set():
    cube = lodestone.CuboidMagnet(lodestone.Pose(), (0.01, 0.01, 0.01), (0, 0, 1e6))
    before = cube.field((0.0, 0.0, 0.05))
    cube.pose = lodestone.Pose((0.0, 0.0, 0.01))
    np.testing.assert_allclose(cube.field((0.0, 0.0, 0.06)), before, rtol=1e-14)  # 0.06 - 0.01 rounds
    s = lodestone.FieldSourceSet([cube])
    s.set_pose(0, lodestone.Pose((0.0, 0.0, 0.0)))
    np.testing.assert_array_equal(s.field((0.0, 0.0, 0.05)), before)
    with pytest.raises(ValueError, match="source 1"):
        lodestone.FieldSourceSet([cube, lodestone.UniformField((0, 0, 1))]).set_pose(1, lodestone.Pose())


def test_time_profiles():
    assert lodestone.TimeProfile.ramp(1.0, 3.0, 0.0, 2.0)(2.0) == 1.0
    assert lodestone.TimeProfile.sine(2.0, 0.25)(1.0) == pytest.approx(2.0, rel=1e-15)
    k = lodestone.TimeProfile.keyframes([0.0, 1.0, 3.0], [0.0, 4.0, 0.0])
    assert (k(-1.0), k(0.5), k(2.0), k(9.0)) == (0.0, 2.0, 2.0, 0.0)


def test_laws():
    mat = lodestone.paper_material()
    assert mat.kind == lodestone.LawKind.LANGEVIN
    assert mat.saturation == pytest.approx(8.27e4, rel=1e-3)
    H = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1e9]])
    M = mat.magnetization(H, mat.number_density)
    np.testing.assert_allclose(M[0], [mat.low_field_susceptibility, 0, 0], rtol=1e-6)
    assert M[1][2] == pytest.approx(mat.saturation, rel=1e-3)
    lin = lodestone.linear_material(0.5, 1e23)
    np.testing.assert_allclose(lin.magnetization(H, 0.5e23), 0.25 * H, rtol=1e-15)
    assert lodestone.magnetization_from_remanence(1.2566370614359173) == pytest.approx(1e6, rel=1e-9)
