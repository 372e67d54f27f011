"""The Python layer's call overhead: the wall time of a call from Python
minus the wall time of the engine's own call inside it (``Run.engine_seconds``:
the Rust call alone, measured in the worker thread), for the chain of
pendulums' forced response (Li, Jain & Haller 2023, Fig. 15, O(3), O(5), O(7)
of the 405-state DAE) and the frequency divider's scene (``zoo/divider_frc``,
its forced response and full-system steady states). What the difference holds:
the worker thread, the GIL hand-over, the files handed to Python as bytes and
``summary.json`` parsed.

Run after ``cargo build --release --workspace && python3 -m pip install
./python``, with ``SSM_PLUGIN_PATH=target/release``:

    python3 python/benches/overhead.py [repetitions]

Prints, per case, the engine's seconds and the overhead in milliseconds and
in percent of the engine's time, each as mean +- standard deviation.
"""

import pathlib
import statistics
import sys
import time
import warnings

import ssm

ROOT = pathlib.Path(__file__).resolve().parents[2]

CHAIN_FRC = {
    "ssm": {"master_pairs": [1], "order": 7},
    "spectrum": {"method": "sparse", "modes": 8},
    "coordinates": ["phi_n", "x1"],
    "frc": {
        "epsilon": [0.6],
        "omega_range": [1.8, 2.2],
        "orders": [3, 5, 7],
        "rho_max": 25.0,
        "nonautonomous_order": 0,
    },
}


def measure(call, repetitions):
    """(engine seconds, overhead seconds) of each of ``repetitions`` calls,
    after one call that warms the caches."""
    call()
    rows = []
    for _ in range(repetitions):
        t0 = time.perf_counter()
        run = call()
        wall = time.perf_counter() - t0
        rows.append((run.engine_seconds, wall - run.engine_seconds))
    return rows


def report(name, rows):
    engine = [e for e, _ in rows]
    over = [o for _, o in rows]
    share = [o / e for e, o in rows]
    print(
        f"{name}: engine {statistics.mean(engine):.4f} +- "
        f"{statistics.stdev(engine):.4f} s; overhead "
        f"{1e3 * statistics.mean(over):.2f} +- {1e3 * statistics.stdev(over):.2f} ms "
        f"= {100 * statistics.mean(share):.3f} +- {100 * statistics.stdev(share):.3f} %"
        f" ({len(rows)} calls)"
    )


def main():
    repetitions = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    warnings.simplefilter("ignore", ssm.errors.SsmWarning)
    chain = ssm.from_scene(ROOT / "zoo" / "pendulum_chain_fig15.toml")
    report(
        "chain of pendulums, FRC O(3, 5, 7)",
        measure(lambda: ssm.run(chain, CHAIN_FRC, progress=False), repetitions),
    )
    divider = ROOT / "zoo" / "divider_frc.toml"
    report(
        "divider scene (zoo/divider_frc.toml)",
        measure(
            lambda: ssm.run_scene(divider, progress=False), max(3, repetitions // 3)
        ),
    )


if __name__ == "__main__":
    main()
