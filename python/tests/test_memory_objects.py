"""Creating stages and raising errors 1,000 times does not grow the process
(the measure and bound of test_memory.py, which it shares)."""
import lodestone
from conftest import ball_particles, stage_sources
from test_memory import BOUND_BYTES, growth, small_grid


def test_fresh_stages_and_errors_do_not_grow_the_process():
    x, n = ball_particles(200)
    sources = stage_sources()

    def call():
        stage = lodestone.MagneticForceStage(small_grid(), lodestone.paper_material())
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
