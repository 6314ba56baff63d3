"""numpy arrays in and out: dtypes, strides, shapes, outputs and aliasing."""
import numpy as np
import pytest

import lodestone
from conftest import ball_particles, bits, stage_grid, stage_sources


def forces_of(x, n, out=None):
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
    stage.run(x, n, stage_sources())
    return stage.particle_forces(x, n, out=out)


def test_float32_inputs_equal_their_float64_conversion():
    x, n = ball_particles(400)
    x32, n32 = x.astype(np.float32), n.astype(np.float32)
    expected = forces_of(x32.astype(np.float64), n32.astype(np.float64))
    got = forces_of(x32, n32)
    assert got.dtype == np.float64 and got.shape == (400, 3)
    np.testing.assert_array_equal(bits(got), bits(expected))
    # float32 differs from the float64 run (the conversion is real, not a reinterpretation).
    assert not np.array_equal(bits(forces_of(x, n)), bits(got))


@pytest.mark.parametrize("layout", ["fortran", "column_stride", "row_stride", "negative_stride"])
def test_strided_and_non_contiguous_views_give_the_contiguous_result(layout):
    x, n = ball_particles(400)
    expected = forces_of(x, n)
    if layout == "fortran":
        xv, nv = np.asfortranarray(x), n
    elif layout == "column_stride":
        big = np.zeros((400, 6))
        big[:, ::2] = x
        xv, nv = big[:, ::2], n
    elif layout == "row_stride":
        big, bign = np.zeros((800, 3)), np.zeros(800)
        big[::2], bign[::2] = x, n
        xv, nv = big[::2], bign[::2]
    else:
        xv, nv = x[::-1].copy()[::-1], n[::-1].copy()[::-1]
    assert not xv.flags.c_contiguous
    np.testing.assert_array_equal(bits(forces_of(xv, nv)), bits(expected))


def test_lists_are_accepted():
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
    stage.run([[0.0, 0.0, 0.01], [0.001, 0.0, 0.01]], [1e15, 1e15], stage_sources())
    assert stage.particle_forces([[0.0, 0.0, 0.01], [0.001, 0.0, 0.01]], [1e15, 1e15]).shape == (2, 3)


@pytest.mark.parametrize("bad, message", [
    (np.zeros((10, 2)), "positions: expected an array of shape (N, 3), got shape (10, 2)"),
    (np.zeros(30), "positions: expected an array of shape (N, 3), got shape (30,)"),
    (np.zeros((10, 3, 1)), "positions: expected an array of shape (N, 3), got shape (10, 3, 1)"),
    (np.zeros((10, 3), dtype=np.int64), "positions: expected float32 or float64 values, got dtype int64"),
    (np.zeros((10, 3), dtype=np.complex128), "positions: expected float32 or float64 values, got dtype complex128"),
    (np.zeros((10, 3), dtype=np.float16), "positions: expected float32 or float64 values, got dtype float16"),
    ("abc", "positions: expected float32 or float64 values"),
    (np.zeros((10, 3), dtype=">f8"), "positions: expected native (little-endian) byte order, got dtype >f8"),
])
def test_wrong_shapes_and_dtypes_raise_value_error_naming_argument_and_shape(bad, message):
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
    with pytest.raises(ValueError) as e:
        stage.run(bad, np.zeros(10), stage_sources())
    assert message in str(e.value)


def test_counts_must_match_the_positions():
    x, n = ball_particles(10)
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
    with pytest.raises(ValueError, match=r"counts: expected shape \(10,\) \(one value per particle\), got shape \(9,\)"):
        stage.run(x, n[:9], stage_sources())
    with pytest.raises(ValueError, match=r"counts: expected an array of shape \(N,\), got shape \(10, 1\)"):
        stage.run(x, n[:, None], stage_sources())


def test_out_array_is_written_in_place():
    x, n = ball_particles(300)
    expected = forces_of(x, n)
    out = np.full((300, 3), np.nan)
    got = forces_of(x, n, out=out)
    assert np.shares_memory(got, out)
    np.testing.assert_array_equal(bits(out), bits(expected))


def test_out_arrays_that_alias_inputs_or_are_unusable_are_refused(stage_run):
    stage, x, n, _ = stage_run
    xx = x.copy()
    with pytest.raises(ValueError, match="out: shares memory with positions"):
        stage.particle_forces(xx, n, out=xx)
    both = np.zeros((len(x), 4))
    both[:, 0] = n
    both[:, 1:] = x
    with pytest.raises(ValueError, match="out: expected a C-contiguous float64 array"):
        stage.particle_forces(x, both[:, 0], out=both[:, 1:])
    packed = np.zeros(len(x) * 3 + len(x))
    counts_view = packed[len(x) * 3 - 5:len(x) * 4 - 5]  # overlaps the tail of the out region
    counts_view[:] = n
    with pytest.raises(ValueError, match="out: shares memory with counts"):
        stage.particle_forces(x, counts_view, out=packed[:len(x) * 3].reshape(-1, 3))
    with pytest.raises(ValueError, match=r"out: expected an array of shape \(2000, 3\), got shape \(5, 3\)"):
        stage.particle_forces(x, n, out=np.zeros((5, 3)))
    with pytest.raises(ValueError, match="out: expected a C-contiguous float64 array, got dtype float32"):
        stage.particle_forces(x, n, out=np.zeros((len(x), 3), dtype=np.float32))
    ro = np.zeros((len(x), 3))
    ro.flags.writeable = False
    with pytest.raises(ValueError, match="out: the array is read-only"):
        stage.particle_forces(x, n, out=ro)


def test_grid_fields_are_read_only_views_indexed_ijk(stage_run):
    stage, x, n, sources = stage_run
    H = stage.field
    assert H.shape == (21, 21, 16, 3) and H.dtype == np.float64
    assert not H.flags.writeable
    assert np.shares_memory(H, stage.field)  # the stage's storage, no copy
    with pytest.raises(ValueError):
        H[0, 0, 0, 0] = 1.0
    # [i, j, k] is node (i, j, k): the applied field there (outside the magnet) is the sources' field.
    grid = stage.grid
    for i, j, k in [(2, 5, 12), (20, 0, 15), (10, 10, 8)]:
        node = grid.origin + grid.dx * np.array([i, j, k])
        np.testing.assert_allclose(stage.applied_field[i, j, k], sources.field(node), rtol=1e-12, atol=1e-9)
    assert stage.density.shape == (21, 21, 16)
    assert stage.density.sum() * grid.dx ** 3 == pytest.approx(n.sum(), rel=1e-12)


def test_density_input_orders_and_shapes():
    x, n = ball_particles(500)
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
    stage.run(x, n, stage_sources())
    density = np.array(stage.density)
    phi = np.array(stage.potential)
    for layout in (np.asfortranarray(density), np.ascontiguousarray(density), density.astype(np.float32).astype(np.float64)):
        other = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
        other.run_on_density(layout, stage_sources())
        np.testing.assert_allclose(other.potential, phi, rtol=1e-6, atol=1e-9 * np.abs(phi).max())
    with pytest.raises(ValueError, match=r"density: expected an array of shape \(21, 21, 16\) \(one value per grid node\), got shape \(16, 21, 21\)"):
        stage.run_on_density(np.zeros((16, 21, 21)), stage_sources())

