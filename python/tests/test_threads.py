"""Long work behaves as Python users expect: the GIL is released while the
engine computes, so another Python thread runs meanwhile."""

import threading
import time

import numpy as np
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
