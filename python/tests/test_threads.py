"""Long work behaves as Python users expect: the GIL is released while the
engine computes, so another Python thread runs meanwhile; Ctrl-C stops it
within a second or two; its progress reaches a callback or a tqdm bar."""

import os
import signal
import threading
import time

import numpy as np
import pytest
import ssm


def test_another_thread_runs_during_a_long_analysis():
    """A 40-DOF chain's SSM to O(19) over two master pairs takes about a
    second; a Python thread counting meanwhile (1 ms sleeps) advances for
    at least a third of the elapsed milliseconds (with the GIL held
    throughout, it could not advance until the end)."""
    n = 40
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    idx = np.array([[i, i, i, i] for i in range(n)])
    model = ssm.from_arrays(
        np.eye(n), K, rayleigh=(0.01, 0.001), f3=(idx, np.full(n, 0.3)), fext=np.ones(n)
    )
    done = threading.Event()
    result = {}

    def work():
        result["ssm"] = ssm.compute_ssm(model, [1, 2], 19)
        done.set()

    worker = threading.Thread(target=work)
    counted = 0
    started = time.perf_counter()
    worker.start()
    while not done.is_set():
        counted += 1
        time.sleep(0.001)
    worker.join()
    elapsed = time.perf_counter() - started
    assert result["ssm"].order == 19
    assert elapsed > 0.3, elapsed
    assert counted >= elapsed * 1000 / 3, (counted, elapsed)


def chain(n=40, damping=(0.01, 0.001)):
    """A chain of ``n`` unit masses with cubic springs to ground."""
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    idx = np.array([[i, i, i, i] for i in range(n)])
    return ssm.from_arrays(
        np.eye(n),
        K,
        rayleigh=damping,
        f3=(idx, np.full(n, 0.3)),
        fext=np.ones(n),
        outputs={"x": n - 1},
    )


def interrupted_after(seconds, call):
    """Sends this process SIGINT ``seconds`` after starting ``call`` (Ctrl-C
    at a terminal) and returns how long ``call`` took to raise
    ``KeyboardInterrupt`` after the signal."""
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    started = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            call()
    finally:
        timer.cancel()
    return time.perf_counter() - started - seconds


def test_ctrl_c_stops_a_long_ssm_within_two_seconds():
    """The 40-DOF chain's SSM over two pairs to O(31) takes about 12 s here
    (half of it composing ``F(W)``, a sixth enumerating the multi-indices'
    splits); Ctrl-C half a second in raises ``KeyboardInterrupt`` within 2 s
    (the enumeration, the composition and the solves stop at the next
    monomial or multi-index; measured 0.03 s at 0.3 to 4 s in), and the
    package computes again at once."""
    model = chain()
    late = interrupted_after(0.5, lambda: ssm.compute_ssm(model, [1, 2], 31))
    assert late < 2.0, late
    assert ssm.compute_ssm(model, [1], 5).order == 5


def test_ctrl_c_stops_full_system_integrations_within_two_seconds():
    """A plan's validation integrates the lightly damped chain to its steady
    states at six frequencies (about 5 s, two at a time on the worker
    threads): Ctrl-C half a second in stops every integration at its next
    step, and the run raises ``KeyboardInterrupt`` within 2 s (measured
    0.01 s) with no result."""
    model = chain(damping=(0.001, 0.0001))
    plan = {
        "ssm": {"order": 3},
        "coordinates": ["x"],
        "frc": {"epsilon": [0.001], "omega_range": [0.05, 0.1]},
        "validation": {
            "steady_state": {
                "epsilon": 0.001,
                "omegas": [0.06, 0.065, 0.07, 0.075, 0.08, 0.085],
                "delta": 1e-8,
                "max_periods": 20000,
            }
        },
    }
    late = interrupted_after(0.5, lambda: ssm.run(model, plan, progress=False))
    assert late < 2.0, late


@pytest.mark.filterwarnings("ignore::ssm.errors.SsmWarning")
def test_progress_reaches_a_callback_and_a_failing_callback_stops_the_work():
    """A run reports its stages in order to the callback (the spectrum
    first, writing the outputs last); an exception raised by the callback
    stops the work and comes back unchanged."""
    model = chain(n=8)
    plan = {
        "ssm": {"order": 5},
        "coordinates": ["x"],
        "frc": {"epsilon": [0.001], "omega_range": [0.3, 0.4]},
    }
    heard = []
    ssm.run(model, plan, progress=lambda stage, detail: heard.append(stage))
    assert heard[0] == "spectrum" and heard[-1] == "writing outputs", heard

    class Stop(Exception):
        pass

    def refuse(stage, detail):
        raise Stop(stage)

    with pytest.raises(Stop, match="spectrum"):
        ssm.compute_ssm(model, [1], 5, progress=refuse)
    with pytest.raises(ssm.errors.InputError, match="progress"):
        ssm.compute_ssm(model, [1], 5, progress="yes")


@pytest.mark.filterwarnings("ignore::ssm.errors.SsmWarning")
def test_progress_draws_a_tqdm_bar_when_asked(capsys):
    """``progress=True`` draws a tqdm bar on stderr for a call that lasts
    longer than its half-second delay (the 40-DOF chain's SSM to O(23),
    about 2 s), naming the stage; ``progress=False`` draws nothing."""
    model = chain()
    ssm.compute_ssm(model, [1, 2], 23, progress=True)
    assert "SSM" in capsys.readouterr().err
    ssm.compute_ssm(model, [1, 2], 23, progress=False)
    assert capsys.readouterr().err == ""
