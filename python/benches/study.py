"""A study's cost on Dask: the per-point overhead of the Dask path against a
direct call (the same plans run by ``ssm.run`` in a loop, minus nothing: the
difference is the task's scheduling, the point's record written to Parquet
and the figures read back), and the speed-up of two single-threaded workers
over one on the forced responses of the spatial oscillator (Li, Jain &
Haller 2023, Sect. 5.1), with each worker's resident memory.

Run after ``cargo build --release --workspace && python3 -m pip install
./python``, with ``SSM_PLUGIN_PATH=target/release``:

    python3 python/benches/study.py [points]

Prints the serial loop's seconds per point, the overhead per point in
milliseconds (against the loop, and within one run: the worker's wall time
minus the points' own seconds), the speed-up and the workers' memory, each as
mean +- standard deviation over three repetitions.
"""

import statistics
import sys
import tempfile
import time
import warnings

import numpy as np
import ssm
import ssm.study as S
from dask.distributed import Client, LocalCluster

PLAN = {
    "ssm": {"order": 5},
    "coordinates": ["x1"],
    "frc": {"epsilon": [0.01], "omega_range": [1.8, 2.2], "points": 120},
}


def study(n):
    return S.Study(
        model=S.Plugin("spatial-oscillator"),
        plan=PLAN,
        points=S.grid(
            {
                "frc.epsilon": np.linspace(0.002, 0.02, n // 4),
                "model.zeta1": np.linspace(0.01, 0.03, 4),
            }
        ),
    )


def serial(st):
    t0 = time.perf_counter()
    for point in st.points.values:
        model = S._model(st.model, {"zeta1": point["model.zeta1"]})
        S.figures(ssm.run(model, S._plan_at(PLAN, point), progress=False), point)
    return time.perf_counter() - t0


def on_cluster(st, workers):
    with (
        LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
        ) as cluster,
        Client(cluster) as client,
    ):
        S.run(study(8), tempfile.mkdtemp(), client)  # warm the workers
        t0 = time.perf_counter()
        data = S.run(st, tempfile.mkdtemp(), client)
        seconds = time.perf_counter() - t0
        memory = client.run(
            lambda dask_worker: dask_worker.monitor.get_process_memory()
        )
        busy = float(data["seconds"].sum())
        return seconds, [m / 2**20 for m in memory.values()], busy


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 80
    warnings.simplefilter("ignore")
    st = study(n)
    serial(study(8))  # warm
    rows = []
    for _ in range(3):
        loop = serial(st)
        one, mem1, busy = on_cluster(st, 1)
        two, mem2, _ = on_cluster(st, 2)
        rows.append((loop, one, two, mem1, mem2, busy))
    per = [r[0] / n for r in rows]
    over = [(r[1] - r[0]) / n for r in rows]
    # the same in one run: the single worker's wall time minus the points'
    # own seconds (model, run, figures), i.e. scheduling, record, read-back
    inside = [(r[1] - r[5]) / n for r in rows]
    speed = [r[1] / r[2] for r in rows]
    mem = [m for r in rows for m in r[4]]

    def ms(xs):
        return f"{1e3 * statistics.mean(xs):.1f} +- {1e3 * statistics.stdev(xs):.1f} ms"

    print(f"{n} points: serial {ms(per)} a point")
    print(f"Dask overhead (1 worker against the loop): {ms(over)} a point")
    print(
        f"Dask overhead (1 worker, wall minus the points' own time): {ms(inside)} a point"
    )
    print(
        f"speed-up of 2 workers over 1: {statistics.mean(speed):.2f} +- "
        f"{statistics.stdev(speed):.2f}; worker memory "
        f"{statistics.mean(mem):.0f} +- {statistics.stdev(mem):.0f} MiB"
    )


if __name__ == "__main__":
    main()
