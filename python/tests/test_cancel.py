"""Cancellation, progress callbacks and the GIL.

A long scene run and a loop of stage solves are interrupted by SIGINT sent to
the process from a timer thread; the KeyboardInterrupt must reach the caller
within 100 ms of the signal. Progress callables can stop a run by returning
False, and their exceptions propagate. Runs release the GIL.
"""
import json
import os
import signal
import threading
import time

import numpy as np
import pytest

import lodestone
from conftest import SOURCE_DIR, ball_particles, stage_grid, stage_sources

LATENCY_BOUND_S = 0.100


def long_scene():
    # The cube scene on a coarse grid, 150 frames (seconds of work): substeps of
    # about 0.1 ms, and one field solve a frame whose substep takes 20-40 ms on
    # a loaded 2-core machine. A KeyboardInterrupt is noticed after the
    # substep it falls in, so that is the latency.
    return lodestone.Scene.load(str(SOURCE_DIR / "examples/scenes/cube_langevin.json"), dx=0.05)


def interrupt_after(seconds):
    sent = {}

    def fire():
        sent["t"] = time.perf_counter()
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(seconds, fire)
    timer.start()
    return sent, timer


def test_keyboard_interrupt_stops_a_scene_run_at_the_substep_in_progress():
    # The scene runner's hook is the end of each substep (where `lodestone run`
    # stops on Ctrl-C): the run must stop at the first hook after the signal,
    # so no substep after the one in progress completes. The latency is then
    # the rest of that substep (milliseconds; a field-solve substep takes
    # tens of ms on this scene, more on a loaded machine), printed here.
    scene = long_scene()
    polls = []

    def progress(report):
        if report["stage"] == "substep":
            polls.append(time.perf_counter())
        return True

    # After 1 s: past the first (cold) field solve, whose substep is the longest.
    sent, timer = interrupt_after(1.0)
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        scene.run(progress=progress)
    caught = time.perf_counter()
    timer.join()
    gaps = np.diff([t0] + polls)
    in_progress = caught - polls[-1]  # the substep the signal fell in, up to the exception
    print(f"scene run: interrupted after {caught - t0:.3f} s, {(caught - sent['t']) * 1e3:.1f} ms after the signal; "
          f"{len(polls)} substeps, median {np.median(gaps) * 1e3:.2f} ms, longest {gaps.max() * 1e3:.1f} ms; "
          f"the interrupted substep took {in_progress * 1e3:.1f} ms")
    assert len(polls) > 10  # the run was under way when the signal came
    assert polls[-1] < sent["t"]  # no substep was completed and let through after the signal


def test_keyboard_interrupt_stops_a_field_solve_inside_a_scene_run():
    # The scene runner also polls after each Newton iteration of the field
    # solve inside a substep. A signal sent 5 ms after the first Newton report
    # of the first (cold) solve to 1e-10, on this 40^3 field grid, must stop that solve
    # at its next iteration, before the iterations it would have run, and the
    # run at the end of that substep (the stage's nodal fields and force still
    # run): 25-82 ms from the signal on a loaded 2-core machine, printed here.
    path = SOURCE_DIR / "examples/scenes/cube_langevin.json"
    doc = json.loads(path.read_text())
    doc["magnetic"]["tolerance"] = 1e-10  # more Newton iterations to stop early

    def load():
        return lodestone.Scene.parse(json.dumps(doc), str(path), dx=0.033)

    # Uninterrupted: the Newton iterations of the first solve.
    first_solve = []

    def count(report):
        if report["stage"] == "substep":
            return False  # the first substep holds the first solve
        first_solve.append(report["iteration"])
        return True

    load().run(frames=1, progress=count)
    assert len(first_solve) >= 4

    reports = []
    state = {}

    def progress(report):
        reports.append((report["stage"], time.perf_counter()))
        if report["stage"] == "newton" and "sent" not in state:
            state["sent"], state["timer"] = interrupt_after(0.005)
        return True

    with pytest.raises(KeyboardInterrupt):
        load().run(progress=progress)
    caught = time.perf_counter()
    state["timer"].join()
    sent = state["sent"]["t"]
    before = [stage for stage, t in reports if t <= sent]
    after = [stage for stage, t in reports if t > sent]
    print(f"scene run, field solve: {len(before)} of its {len(first_solve)} Newton iterations reported before the "
          f"signal, latency {(caught - sent) * 1e3:.1f} ms")
    assert before == ["newton"] * len(before) and len(before) <= len(first_solve) - 2
    assert after == []  # no later iteration and no substep completed after the signal
    assert caught - sent < 0.25  # a gross bound; the solve alone would go on for its remaining iterations


def test_keyboard_interrupt_stops_a_stage_solve_within_100_ms():
    # Cold solves (no warm start) on the reference grid: several Newton
    # iterations a run, each a few ms. Ctrl-C is noticed after the iteration
    # it falls in, so on large grids, whose iterations take longer, the
    # latency is one iteration.
    x, n = ball_particles(4000)
    settings = lodestone.StageSettings()
    settings.warm_start = False
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material(), settings)
    sources = stage_sources()
    # The first run builds the problem and the multigrid hierarchy before its
    # first Newton iteration, the first point where Ctrl-C is noticed; the
    # loop times the runs after it.
    stage.run(x, n, sources)
    sent, timer = interrupt_after(0.3)
    runs = 0
    with pytest.raises(KeyboardInterrupt):
        while True:
            stage.run(x, n, sources)
            runs += 1
    caught = time.perf_counter()
    timer.join()
    print(f"stage: {runs} runs before the signal, latency {(caught - sent['t']) * 1e3:.1f} ms")
    assert caught - sent["t"] < LATENCY_BOUND_S


def test_progress_returning_false_cancels():
    x, n = ball_particles()
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())
    seen = []
    report = stage.run(x, n, stage_sources(), progress=lambda r: seen.append(r) or False)
    assert report.status == "cancelled"
    assert len(seen) == 1 and seen[0]["stage"] == "newton" and seen[0]["iteration"] >= 0
    full = stage.run(x, n, stage_sources(), progress=lambda r: True)
    assert full.converged and full.newton_iterations >= 1

    scene = long_scene()
    solver, frames = scene.run(frames=3, progress=lambda r: r["stage"] != "substep" or r["substep"] < 5)
    assert len(frames) == 1 and frames[0]["cancelled"]
    assert frames[0]["substeps"] == 5


def test_progress_exceptions_propagate():
    x, n = ball_particles()
    stage = lodestone.MagneticForceStage(stage_grid(), lodestone.paper_material())

    def boom(report):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        stage.run(x, n, stage_sources(), progress=boom)
    assert stage.run(x, n, stage_sources()).converged  # the stage is usable afterwards


def test_runs_release_the_gil():
    # A stage run without a progress callable never takes the GIL back until
    # it returns: a thread ticking every millisecond meanwhile shows that the
    # call released it (holding it, the other thread would not tick at all).
    x, n = ball_particles(4000)
    grid = lodestone.Grid((-0.04, -0.04, -0.02), 0.001, (81, 81, 61))
    stage = lodestone.MagneticForceStage(grid, lodestone.paper_material())
    ticks = [0]
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    time.sleep(0.01)
    before = ticks[0]
    t0 = time.perf_counter()
    stage.run(x, n, stage_sources())
    elapsed = time.perf_counter() - t0
    during = ticks[0] - before
    done.set()
    counter.join()
    print(f"{during} ticks of the other thread during a {elapsed:.3f} s run")
    assert elapsed > 0.05 and during > 10
