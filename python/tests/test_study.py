"""Studies on a Dask cluster (a LocalCluster of two single-threaded worker
processes): the same figures as the serial loop, nothing lost or computed
twice when a worker dies or the study is stopped, bad studies refused or
recorded per point."""

import functools
import json
import os
import pathlib
import signal
import time

import numpy as np
import pytest
import ssm
import ssm.study as S
from test_plugins import RELEASE

PLAN = {
    "ssm": {"order": 5},
    "coordinates": ["x1"],
    "frc": {"epsilon": [0.01], "omega_range": [1.8, 2.2], "points": 120},
}


@pytest.fixture(scope="module")
def client():
    """Two worker processes, one thread each (the machine's two cores)."""
    from dask.distributed import Client, LocalCluster

    os.environ["SSM_PLUGIN_PATH"] = str(RELEASE)
    cluster = LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    with Client(cluster) as c:
        yield c
    cluster.close()


def oscillator_study(n_eps=8, n_zeta=5):
    return S.Study(
        model=S.Plugin("spatial-oscillator"),
        plan=PLAN,
        points=S.grid(
            {
                "frc.epsilon": np.linspace(0.002, 0.02, n_eps),
                "model.zeta1": np.linspace(0.01, 0.03, n_zeta),
            }
        ),
    )


def test_a_grid_study_gives_the_serial_loop_s_figures(client, tmp_path):
    """40 forced responses of the spatial oscillator (Li, Jain & Haller
    2023, Sect. 5.1) over the forcing amplitude and the damping of x1 on two
    workers (8 x 5, 0.24 s each; CI's budget): every figure equals the serial
    loop's over the same plans (a
    determinism check across the two ways of running them), and the peak
    grows with the forcing and falls with the damping (the linear limit's
    ``eps / (2 zeta omega^2)`` ordering)."""
    study = oscillator_study()
    data = S.run(study, tmp_path / "store", client)
    assert dict(data.sizes) == {"frc.epsilon": 8, "model.zeta1": 5}
    assert not np.any(data["error"].notnull().to_numpy())
    for point in study.points.values[::13]:
        model = ssm.from_plugin("spatial-oscillator", zeta1=point["model.zeta1"])
        run = ssm.run(model, S._plan_at(PLAN, point), progress=False)
        serial = S.figures(run, point)
        at = data.sel({k: v for k, v in point.items()})
        for key in ("peak_amplitude", "peak_omega", "frc_error_estimate"):
            assert float(at[key]) == serial[key], key
    peak = data["peak_amplitude"].to_numpy()
    assert np.all(np.diff(peak, axis=0) > 0) and np.all(np.diff(peak, axis=1) < 0)


def test_a_worker_killed_mid_study_loses_and_repeats_no_point(client, tmp_path):
    """One worker process is killed (SIGKILL) after 8 points have finished:
    Dask reschedules its tasks, and the store ends with one whole record per
    point (each readable, each point once, no partial file)."""
    study = oscillator_study(6, 5)
    pids = client.run(os.getpid)
    killed = []

    def progress(finished, failed, remaining, seconds_left):
        if finished == 8 and not killed:
            victim = min(pids.values())
            os.kill(victim, signal.SIGKILL)
            killed.append(victim)

    store = tmp_path / "store"
    data = S.run(study, store, client, progress=progress)
    assert killed
    records = sorted((store / "points").glob("*.parquet"))
    assert [int(p.stem) for p in records] == list(range(30))
    assert not [p for p in (store / "points").iterdir() if p.suffix != ".parquet"]
    assert int(data["peak_amplitude"].notnull().sum()) == 30
    client.wait_for_workers(2)


def test_a_stopped_study_reruns_only_the_missing_points(client, tmp_path):
    """A study stopped after 6 of 20 points (its progress callback raises
    KeyboardInterrupt, as Ctrl-C would) keeps what finished; the rerun
    computes only the rest, and the result is the uninterrupted study's."""
    study = oscillator_study(4, 5)
    store = tmp_path / "store"

    def stop(finished, failed, remaining, seconds_left):
        if finished == 6:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        S.run(study, store, client, progress=stop)
    client.cancel(list(client.futures))
    # a point already running on a worker when the study stopped finishes
    # and is kept: wait for the workers to be idle before counting
    deadline = time.monotonic() + 60
    while any(client.processing().values()) and time.monotonic() < deadline:
        time.sleep(0.05)
    before = S.done(store)
    assert 6 <= len(before) < 20
    seen = []
    data = S.run(study, store, client, progress=lambda *a: seen.append(a))
    assert len(seen) == 20 - len(before)
    whole = S.run(study, tmp_path / "whole", client)
    assert data.equals(whole.drop_vars("seconds").assign(seconds=data["seconds"]))


def test_bad_studies_are_refused_or_recorded_per_point(client, tmp_path):
    """An unknown plan section and an empty range are StudyErrors before
    anything runs; a point whose analysis fails (a reversed frequency
    range) records its typed error and the others run; a store written by
    another study is refused."""
    with pytest.raises(S.StudyError, match="forcing.epsilon"):
        S.grid({"forcing.epsilon": [0.01]})
    with pytest.raises(S.StudyError, match="empty"):
        S.grid({"frc.epsilon": []})
    with pytest.raises(S.StudyError, match="empty"):
        S.sample({"frc.epsilon": (0.02, 0.01)}, 10, seed=1)
    study = S.Study(
        model=S.Plugin("spatial-oscillator"),
        plan=PLAN,
        points=S.points(
            [{"frc.omega_range": [1.8, 2.2]}, {"frc.omega_range": [2.2, 1.8]}]
        ),
    )
    table = S.run(study, tmp_path / "store", client)
    assert table["error"].isna().tolist() == [True, False]
    assert table["error_type"][1] == "InputError" and "omega_range" in table["error"][1]
    other = oscillator_study(2, 2)
    with pytest.raises(S.StudyError, match="another study"):
        S.run(other, tmp_path / "store", client)


def test_a_seeded_sample_is_the_same_sample():
    """Determinism check: the same seed draws the same points, another seed
    others; every value lies in its range."""
    ranges = {"frc.epsilon": (0.001, 0.02), "model.zeta1": (0.01, 0.03)}
    a = S.sample(ranges, 8, seed=7)
    assert a == S.sample(ranges, 8, seed=7) and a != S.sample(ranges, 8, seed=8)
    for name, (low, high) in ranges.items():
        values = [p[name] for p in a.values]
        assert len(set(values)) == 8 and all(low <= v <= high for v in values)
    json.dumps(a.values)  # plain numbers: the store's fingerprint takes them


def test_backbone_shifts_of_a_study_are_the_closed_form(client, tmp_path):
    """Reference: the O(3) normal form of the Duffing oscillator (unit
    master eigenvector; ``test_answers``), ``omega(rho) = w_d + 3 kappa
    rho^2 / (2 w_d (1 + w^2))``: the study's backbone shift at ``rho = 0.1``
    over three cubic stiffnesses (the ``duffing`` plugin's ``kappa``) is
    ``omega(0.1) / w_d - 1`` within 1e-10 (0.1 is a point of the backbone's
    grid, so no interpolation error enters; ``backbone.csv`` holds 11
    significant digits of each frequency)."""
    study = S.Study(
        model=S.Plugin("duffing"),
        plan={
            "ssm": {"order": 3},
            "coordinates": ["x"],
            "backbone": {"rho_max": 0.2, "points": 101},
        },
        points=S.grid({"model.kappa": [-0.5, 0.5, 2.0]}),
        answers=functools.partial(S.figures, backbone_at=(0.1,)),
    )
    data = S.run(study, tmp_path / "store", client, progress=False)
    zeta, w = 0.01, 1.0  # the plugin's defaults
    wd = w * np.sqrt(1 - zeta * zeta)
    kappa = data["model.kappa"].to_numpy()
    expected = 3 * kappa * 0.1**2 / (2 * wd * (1 + w * w)) / wd
    gap = np.abs(data["backbone_shift@0.1"].to_numpy() - expected)
    assert gap.max() < 1e-10, gap


def test_the_command_line_s_sharded_store_reads_as_the_python_study(client, tmp_path):
    """``ssm-engine study`` over the bundled base scene in two shards (as a
    Slurm array runs it), read by :func:`ssm.study.read`, gives the grid
    and every figure of the same study run by Dask from Python on the
    plugin's model with the scene's plan written as a dictionary: two doors
    (TOML scene and study file, Python plan and points) to one engine, so
    the figures agree bit for bit (a determinism check)."""
    import shutil
    import subprocess

    root = pathlib.Path(__file__).resolve().parents[2]
    shutil.copy(root / "zoo/studies/spatial_oscillator_frc.toml", tmp_path)
    (tmp_path / "s.study.toml").write_text(
        'scene = "spatial_oscillator_frc.toml"\n'
        "[[grid]]\n"
        'parameter = "frc.epsilon"\n'
        "values = [0.004, 0.02, 0.05]\n"
        "[[grid]]\n"
        'parameter = "model.zeta1"\n'
        "values = [0.01, 0.025]\n"
    )
    store = tmp_path / "cli"
    for shard in ("1/2", "2/2"):
        subprocess.run(
            [RELEASE / "ssm-engine", "study", tmp_path / "s.study.toml"]
            + ["--store", store, "--shard", shard],
            check=True,
            capture_output=True,
            env={**os.environ, "SSM_PLUGIN_PATH": str(RELEASE), "CI": "1"},
        )
    cli = S.read(store)
    plan = {
        "ssm": {"master_pairs": [1], "order": 5},
        "coordinates": ["x1"],
        "frc": {"epsilon": [0.01], "omega_range": [1.8, 2.2], "points": 120},
    }
    study = S.Study(
        model=S.Plugin("spatial-oscillator"),
        plan=plan,
        points=S.grid(
            {"frc.epsilon": [0.004, 0.02, 0.05], "model.zeta1": [0.01, 0.025]}
        ),
    )
    python = S.run(study, tmp_path / "python", client, progress=False)
    assert dict(cli.sizes) == {"frc.epsilon": 3, "model.zeta1": 2}
    assert not np.any(cli["error"].notnull().to_numpy())
    assert int(np.count_nonzero(cli["fold_omegas"].to_numpy() != "[]")) >= 1
    for key in python.data_vars:
        if key != "seconds":
            assert cli[key].equals(python[key]), key
