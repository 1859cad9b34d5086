"""The GIL is released during a run, progress is reported, Ctrl-C stops a run."""

import _thread
import signal
import threading
import time

import numpy as np
import pytest

import demcon


def test_gil_is_released_during_a_run(homogeneous):
    scene = demcon.Scene.from_file(homogeneous)
    count = 0
    done = threading.Event()

    def spin():
        nonlocal count
        while not done.is_set():
            count += 1
            time.sleep(0.001)

    t = threading.Thread(target=spin)
    t.start()
    try:
        r = scene.run()
    finally:
        done.set()
        t.join()
    # a run of a few tenths of a second leaves the other thread dozens of turns at 1 ms each
    assert r.wall_s > 0.0
    assert count >= 10, (count, r.wall_s)


def test_progress_callback_sees_the_stages(homogeneous):
    seen = []
    demcon.Scene.from_file(homogeneous).run(progress=lambda stage, done, total: seen.append(stage))
    assert "packing" in seen and "solve" in seen, seen


def interrupted_after(seconds, call):
    """Runs `call` with a Ctrl-C (SIGINT) sent `seconds` later; it must raise KeyboardInterrupt."""
    # A process started in the background (a CI job) may inherit SIGINT ignored, and then
    # `interrupt_main` does nothing: give SIGINT Python's own handler meanwhile.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(seconds, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            call()
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)


def test_keyboard_interrupt_stops_a_long_run(long_transient, tmp_path):
    scene = demcon.Scene.from_file(long_transient)
    out = tmp_path / "out"
    t0 = time.perf_counter()
    interrupted_after(1.5, lambda: scene.run(out=out))
    elapsed = time.perf_counter() - t0
    assert elapsed < 30.0, elapsed
    # no partial output
    assert not out.exists() or not any(out.iterdir())


def test_an_interrupted_run_resumes_from_its_checkpoint(tmp_path):
    from conftest import DATA

    scene = demcon.Scene.from_file(DATA / "checkpointed.ron")
    whole = scene.run(out=tmp_path / "whole")
    assert not (tmp_path / "whole.checkpoint").exists()  # a completed run removes it
    out = tmp_path / "cut"
    interrupted_after(0.4 * whole.wall_s, lambda: scene.run(out=out))
    assert (tmp_path / "cut.checkpoint").exists()
    assert not out.exists() or not any(out.iterdir())
    resumed = scene.run(out=out, resume=True)
    assert resumed.resumed["steps"] > 0 and whole.resumed is None
    assert np.array_equal(resumed.temperature, whole.temperature)
    assert not (tmp_path / "cut.checkpoint").exists()
    with pytest.raises(ValueError, match="resume = True"):
        scene.run(resume=True)


def test_keyboard_interrupt_stops_a_packing():
    # 10⁵ spheres to φ = 0.6 take about ten seconds; Ctrl-C stops them within a fraction of one
    t0 = time.perf_counter()
    interrupted_after(0.5, lambda: demcon.pack({"Periodic": {"size": (1.0, 1.0, 1.0)}}, count=100_000, phi=0.6))
    elapsed = time.perf_counter() - t0
    assert elapsed < 5.0, elapsed
