"""Studies: one base plan run at many points (a grid, given points, or a
seeded random sample over parameter ranges) as tasks of a Dask cluster,
each finished point written at once to a store so that a rerun computes
only what is missing.

A study names its model by a recipe that a worker can rebuild (a plugin
with its parameters, a scene file, a model folder, or arrays), so a model
shared by all points is built once per worker, and a point may change the
model's parameters (``"model.<name>"``) as well as any value of the plan
(``"frc.epsilon"``, ``"ssm.order"``, ``"ssm.tolerance"``,
``"frc.omega_range"``, ...). Each point's figures come from
:func:`figures` (or a function of your own): the forced response's peak,
its folds and branch points, the error estimates, the wall time and the
warnings.

The store is a directory: ``study.json`` (what the study is; a store of
another study is refused) and one Parquet file per finished point under
``points/``, written to a temporary name and renamed, so the store never
holds a partial record; a point that fails records its typed error.

Example
-------
>>> import ssm.study
>>> st = ssm.study.Study(
...     model=ssm.study.Plugin("spatial-oscillator"),
...     plan={"ssm": {"order": 5}, "coordinates": ["x1"],
...           "frc": {"epsilon": [0.01], "omega_range": [1.8, 2.2]}},
...     points=ssm.study.grid({"frc.epsilon": [0.005, 0.01],
...                            "model.zeta1": [0.01, 0.02]}),
... )
>>> table = ssm.study.run(st, "store")  # doctest: +SKIP

References
----------
Dask.distributed (``Client``, ``LocalCluster``); on Slurm or PBS the same
``client`` comes from dask-jobqueue (``SLURMCluster``); see
``docs/studies.md``.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import json
import os
import time
import uuid
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import SsmError

__all__ = [
    "Arrays",
    "Files",
    "Plugin",
    "Scene",
    "Study",
    "StudyError",
    "figures",
    "grid",
    "points",
    "run",
    "sample",
]

STORE_VERSION = 1


class StudyError(SsmError, ValueError):
    """A study that cannot run as given: an unknown parameter, an empty
    range, a store of another study (the message names it)."""


# -- the model's recipe -----------------------------------------------------


@dataclass(frozen=True)
class Plugin:
    """A plugin's model: ``plugin`` (a name on ``SSM_PLUGIN_PATH`` or a path
    to its ``.so``), ``model`` (default the plugin's first) and its
    parameters."""

    plugin: str
    model: str = ""
    params: Mapping[str, Any] = field(default_factory=dict)

    def build(self, overrides: Mapping[str, Any]) -> Any:
        """The model with the parameters ``overrides`` over the recipe's."""
        import ssm

        return ssm.from_plugin(self.plugin, self.model, **{**self.params, **overrides})

    def describe(self) -> dict[str, Any]:
        """The recipe as JSON-able data (the study's identity)."""
        return {
            "plugin": self.plugin,
            "model": self.model,
            "params": dict(self.params),
        }


@dataclass(frozen=True)
class Scene:
    """The model of a scene file (its ``[model]`` or its ``[reduce]``)."""

    path: str
    plugins: tuple[str, ...] = ()

    def build(self, overrides: Mapping[str, Any]) -> Any:
        """The scene's model (a scene's model takes no parameters here)."""
        import ssm

        if overrides:
            raise StudyError(
                f"points: a scene's model takes no parameters ({sorted(overrides)}); "
                "use ssm.study.Plugin"
            )
        return ssm.from_scene(self.path, self.plugins)

    def describe(self) -> dict[str, Any]:
        """The recipe as JSON-able data."""
        return {"scene": str(self.path), "plugins": list(self.plugins)}


@dataclass(frozen=True)
class Files:
    """The model of a folder of files, with optional Rayleigh damping
    (``model.alpha``, ``model.beta`` as parameters of the points)."""

    folder: str
    rayleigh: tuple[float, float] | None = None

    def build(self, overrides: Mapping[str, Any]) -> Any:
        """The folder's model, its Rayleigh coefficients overridden."""
        import ssm

        unknown = set(overrides) - {"alpha", "beta"}
        if unknown:
            raise StudyError(
                f"points: a model folder has no parameter {sorted(unknown)}"
            )
        alpha, beta = self.rayleigh or (None, None)
        alpha = overrides.get("alpha", alpha)
        beta = overrides.get("beta", beta)
        rayleigh = None if alpha is None else (float(alpha), float(beta or 0.0))
        return ssm.from_files(self.folder, rayleigh)

    def describe(self) -> dict[str, Any]:
        """The recipe as JSON-able data."""
        return {"files": str(self.folder), "rayleigh": self.rayleigh}


@dataclass(frozen=True, eq=False)
class Arrays:
    """A model from arrays: ``make(**params)`` returns the keyword arguments
    of :func:`ssm.from_arrays` (a module-level function, so that workers can
    import it), with the points' ``model.<name>`` values as ``params``."""

    make: Callable[..., Mapping[str, Any]]
    params: Mapping[str, Any] = field(default_factory=dict)

    def build(self, overrides: Mapping[str, Any]) -> Any:
        """The model of ``make`` at the recipe's and the point's parameters."""
        import ssm

        return ssm.from_arrays(**self.make(**{**self.params, **overrides}))

    def describe(self) -> dict[str, Any]:
        """The recipe as JSON-able data."""
        name = f"{self.make.__module__}.{self.make.__qualname__}"
        return {"arrays": name, "params": dict(self.params)}


# -- points -----------------------------------------------------------------


def _check_parameters(names: Sequence[str]) -> None:
    for name in names:
        head, _, rest = str(name).partition(".")
        if not rest or head not in _PLAN_KEYS | {"model"}:
            raise StudyError(
                f"points: unknown parameter '{name}': give 'model.<parameter>' or "
                f"'<plan section>.<key>' with a section among {sorted(_PLAN_KEYS)}"
            )


_PLAN_KEYS = {
    "ssm",
    "spectrum",
    "backbone",
    "invariance",
    "transient",
    "frc",
    "validation",
    "reference",
    "report",
    "simulate",
}


@dataclass(frozen=True)
class Points:
    """The points of a study: ``values`` (one dictionary per point,
    parameter -> value) and, for a grid, its ``dims`` (parameter -> the
    values along it)."""

    values: tuple[Mapping[str, Any], ...]
    dims: Mapping[str, tuple[Any, ...]] | None = None


def grid(axes: Mapping[str, Sequence[Any]]) -> Points:
    """Every combination of the values of ``axes`` (parameter -> values),
    the last parameter varying fastest."""
    if not axes:
        raise StudyError("points: a grid needs at least one parameter")
    _check_parameters(list(axes))
    dims = {}
    for name, values in axes.items():
        values = tuple(
            _plain(v) for v in np.atleast_1d(np.asarray(values, dtype=object))
        )
        if not values:
            raise StudyError(f"points: the range of '{name}' is empty")
        dims[str(name)] = values
    combos = itertools.product(*dims.values())
    return Points(tuple(dict(zip(dims, c)) for c in combos), dims)


def points(values: Sequence[Mapping[str, Any]]) -> Points:
    """The points ``values`` as given (one dictionary each)."""
    values = tuple({str(k): _plain(v) for k, v in p.items()} for p in values)
    if not values:
        raise StudyError("points: no point given")
    _check_parameters(sorted({k for p in values for k in p}))
    return Points(values)


def sample(ranges: Mapping[str, tuple[float, float]], n: int, seed: int) -> Points:
    """``n`` points drawn uniformly from the boxes ``ranges`` (parameter ->
    ``(low, high)``) by numpy's PCG64 generator seeded with ``seed``."""
    if n <= 0:
        raise StudyError(f"points: a sample of {n} points")
    _check_parameters(list(ranges))
    rng = np.random.default_rng(seed)
    columns = {}
    for name, (low, high) in ranges.items():
        if not (np.isfinite(low) and np.isfinite(high) and high > low):
            raise StudyError(f"points: the range of '{name}' [{low}, {high}] is empty")
        columns[name] = rng.uniform(low, high, n)
    return Points(tuple({k: float(v[i]) for k, v in columns.items()} for i in range(n)))


def _plain(v: Any) -> Any:
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, tuple):
        return list(v)
    return v


# -- the study ----------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Study:
    """A base ``plan`` (the dictionary :func:`ssm.run` takes) run on
    ``model`` (a recipe: :class:`Plugin`, :class:`Scene`, :class:`Files` or
    :class:`Arrays`) at each of ``points``; ``answers(run, point)`` makes a
    point's figures (default :func:`figures`)."""

    model: Any
    plan: Mapping[str, Any]
    points: Points
    answers: Callable[[Any, Mapping[str, Any]], Mapping[str, Any]] | None = None

    def fingerprint(self) -> str:
        """What identifies the study in its store: the model's recipe, the
        base plan and the points."""
        text = json.dumps(
            {
                "model": self.model.describe(),
                "plan": self.plan,
                "points": list(self.points.values),
                "answers": _describe(self.answers),
            },
            sort_keys=True,
            default=str,
        )
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def _describe(answers: Any) -> Any:
    """A function by its importable name (a ``functools.partial`` with its
    arguments), for the study's fingerprint."""
    if answers is None:
        return None
    if isinstance(answers, functools.partial):
        return [_describe(answers.func), list(answers.args), dict(answers.keywords)]
    name = getattr(answers, "__qualname__", type(answers).__qualname__)
    return f"{getattr(answers, '__module__', '')}.{name}"


def _plan_at(plan: Mapping[str, Any], point: Mapping[str, Any]) -> dict[str, Any]:
    """The base plan with the point's plan values set (``section.key``);
    a scalar given for a list-valued key (``frc.epsilon``) becomes a list
    of one."""
    out = json.loads(json.dumps(plan))
    for name, value in point.items():
        head, _, key = name.partition(".")
        if head == "model":
            continue
        section = out.setdefault(head, {})
        if (
            key in ("epsilon", "orders")
            and head == "frc"
            and not isinstance(value, list)
        ):
            value = [value]
        section[key] = value
    return out


def figures(
    run: Any, point: Mapping[str, Any], backbone_at: Sequence[float] = ()
) -> dict[str, Any]:
    """A point's figures from its run: per forced response curve of the
    first output the peak amplitude and its frequency, the frequencies of
    its folds and branch points, its error estimate and ``untrusted``; per
    backbone curve its relative frequency shift ``omega(rho) / omega(0) -
    1`` at each polar amplitude of ``backbone_at`` (linear interpolation
    between the curve's points; NaN beyond it), and the largest backbone
    estimate; the order. (:func:`run_point` adds the wall time, the
    warnings and any error.) Give other amplitudes with
    ``functools.partial(figures, backbone_at=[...])`` as a study's
    ``answers``."""
    summary = run.summary
    out: dict[str, Any] = {}
    if backbone_at and "backbone.csv" in run.files:
        table = run.table("backbone.csv")
        orders = sorted(set(table["order"]))
        for order in orders:
            rows = table[table["order"] == order]
            rho, omega = rows["rho"].to_numpy(), rows["omega"].to_numpy()
            prefix = f"O{order}_" if len(orders) > 1 else ""
            for a in backbone_at:
                shifted = np.interp(a, rho, omega, left=np.nan, right=np.nan)
                out[f"{prefix}backbone_shift@{a:g}"] = float(shifted / omega[0] - 1.0)
    frc = summary.get("frc") or {}
    if frc.get("curves"):
        table = run.table("frc.csv")
        amp = [c for c in table.columns if c.endswith("_linf")]
        for c in frc["curves"]:
            key = (
                f"O{c['order']}" if len({x["order"] for x in frc["curves"]}) > 1 else ""
            )
            rows = table[
                (table["order"] == c["order"]) & (table["epsilon"] == c["epsilon"])
            ]
            prefix = f"{key}_" if key else ""
            if amp and len(rows):
                k = int(rows[amp[0]].to_numpy().argmax())
                out[f"{prefix}peak_amplitude"] = float(rows[amp[0]].to_numpy()[k])
                out[f"{prefix}peak_omega"] = float(rows["omega"].to_numpy()[k])
            bif = [
                b
                for b in frc.get("bifurcations", [])
                if b["order"] == c["order"] and b["epsilon"] == c["epsilon"]
            ]
            out[f"{prefix}fold_omegas"] = sorted(
                b["omega"] for b in bif if b["kind"] == "SN"
            )
            out[f"{prefix}branch_point_omegas"] = sorted(
                b["omega"] for b in bif if b["kind"] == "BP"
            )
            out[f"{prefix}frc_error_estimate"] = c.get("error_estimate")
            out[f"{prefix}frc_untrusted"] = bool(c.get("untrusted", False))
    answers = (summary.get("accuracy") or {}).get("answers", [])
    backbone = [a["error_estimate"] for a in answers if a["answer"] == "backbone"]
    if backbone:
        out["backbone_error_estimate"] = max(e for e in backbone if e is not None)
    out["order"] = (summary.get("accuracy") or {}).get("order")
    return out


# -- one point, on a worker -----------------------------------------------------

_MODELS: dict[str, Any] = {}


def _model(recipe: Any, overrides: Mapping[str, Any]) -> Any:
    """The model of ``recipe`` at ``overrides``, built once per process."""
    key = json.dumps([recipe.describe(), dict(overrides)], sort_keys=True, default=str)
    if key not in _MODELS:
        _MODELS[key] = recipe.build(overrides)
    return _MODELS[key]


def _record_path(store: Path, index: int) -> Path:
    return store / "points" / f"{index:08d}.parquet"


def _write_record(path: Path, record: Mapping[str, Any]) -> None:
    """``record`` as a one-row Parquet file, written under a temporary name
    and renamed: a reader sees the whole record or none (lists and
    dictionaries as JSON text)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    row = {
        k: json.dumps(v) if isinstance(v, (list, dict)) else v
        for k, v in record.items()
    }
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    pq.write_table(pa.Table.from_pylist([row]), tmp)
    os.replace(tmp, path)


def run_point(study: Study, index: int, store: str) -> dict[str, Any]:
    """Runs point ``index`` of ``study`` and writes its record to ``store``
    (a failure records its error); returns the record."""
    import ssm

    point = study.points.values[index]
    overrides = {
        k.partition(".")[2]: v for k, v in point.items() if k.startswith("model.")
    }
    record: dict[str, Any] = {
        "point": index,
        **{f"param:{k}": v for k, v in point.items()},
    }
    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            model = _model(study.model, overrides)
            run = ssm.run(model, _plan_at(study.plan, point), progress=False)
            answers = study.answers or figures
            record.update(answers(run, point))
            record["error"] = None
            record["error_type"] = None
        except Exception as e:  # noqa: BLE001 - a failing point is a record, not a crash
            record["error"] = str(e)
            record["error_type"] = type(e).__name__
    record["seconds"] = time.perf_counter() - started
    record["warnings"] = [str(w.message) for w in caught]
    _write_record(_record_path(Path(store), index), record)
    return record


# -- the study, on a cluster ------------------------------------------------------


def _open_store(study: Study, store: Path) -> None:
    """Creates the store for ``study`` or checks that it holds ``study``."""
    meta = store / "study.json"
    fingerprint = study.fingerprint()
    if meta.is_file():
        held = json.loads(meta.read_text())
        if (
            held.get("fingerprint") != fingerprint
            or held.get("version") != STORE_VERSION
        ):
            raise StudyError(
                f"store: {store} holds another study (fingerprint "
                f"{held.get('fingerprint')}, this one {fingerprint}); give another store"
            )
        return
    if store.exists() and not store.is_dir():
        raise StudyError(f"store: {store} is not a directory")
    if store.exists() and any(store.iterdir()):
        raise StudyError(f"store: {store} is not empty and holds no study")
    (store / "points").mkdir(parents=True, exist_ok=True)
    text = json.dumps(
        {
            "version": STORE_VERSION,
            "fingerprint": fingerprint,
            "points": len(study.points.values),
            "dims": None if study.points.dims is None else list(study.points.dims),
        }
    )
    tmp = store / f".study.json.{uuid.uuid4().hex}.tmp"
    tmp.write_text(text)
    os.replace(tmp, meta)


def done(store: str | Path) -> set[int]:
    """The points the store holds a record of."""
    folder = Path(store) / "points"
    if not folder.exists():
        return set()
    return {int(p.stem) for p in folder.glob("*.parquet") if p.stem.isdigit()}


def read(study: Study, store: str | Path) -> Any:
    """The store's records as a ``pandas.DataFrame`` (one row per point,
    in the points' order), or, for a grid, an ``xarray.Dataset`` with one
    dimension per grid parameter."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    paths = sorted((Path(store) / "points").glob("*.parquet"))
    if not paths:
        raise StudyError(f"store: {store} holds no finished point")
    tables = [pq.read_table(p) for p in paths]
    frame = pa.concat_tables(tables, promote_options="default").to_pandas()
    frame = frame.sort_values("point").reset_index(drop=True)
    for column in frame.columns:
        values = frame[column]
        if (
            values.dtype == object
            and values.map(lambda v: isinstance(v, str) and v[:1] in "[{").all()
        ):
            frame[column] = values.map(json.loads)
    if study.points.dims is None:
        return frame
    dims = [f"param:{d}" for d in study.points.dims]
    table = frame.set_index(dims).drop(columns=["point"])
    list_columns = [
        c for c in table.columns if table[c].map(lambda v: isinstance(v, list)).any()
    ]
    dataset = table.drop(columns=list_columns).to_xarray()
    for c in list_columns:
        dataset[c] = table[c].map(json.dumps).to_xarray()
    return dataset.rename({d: d.removeprefix("param:") for d in dims})


class _TqdmPoints:
    """A ``tqdm`` bar of a study's points: finished of all, failed ones and
    the time left in its postfix."""

    def __init__(self, total: int) -> None:
        from tqdm.auto import tqdm

        self._bar = tqdm(total=total, unit="point", leave=False)

    def __call__(
        self, finished: int, failed: int, remaining: int, left: float | None
    ) -> None:
        self._bar.n = finished
        self._bar.set_postfix(failed=failed, refresh=False)
        self._bar.refresh()

    def close(self) -> None:
        self._bar.close()


def _bar(progress: Any, total: int) -> _TqdmPoints | None:
    """The default progress display: a tqdm bar when ``progress`` is
    ``None`` and tqdm is installed."""
    if progress is not None and progress is not True:
        if progress is not False and not callable(progress):
            raise StudyError(
                f"progress: give a callable, True, False or None, not {progress!r}"
            )
        return None
    try:
        import tqdm  # noqa: F401
    except ImportError:
        return None
    return _TqdmPoints(total)


def run(
    study: Study,
    store: str | Path,
    client: Any = None,
    retries: int = 2,
    progress: Callable[[int, int, int, float | None], None] | bool | None = None,
) -> Any:
    """Runs the points of ``study`` that ``store`` does not hold yet, each as
    a task of the Dask ``client`` (default: a ``LocalCluster`` with one
    single-threaded worker per core, closed at the end), and returns
    :func:`read` of the whole store.

    A task whose worker dies is rescheduled (Dask's ``retries``); a point
    that fails records its error; ``progress(finished, failed, remaining,
    seconds_left)`` is called as points finish (``None``, the default, and
    ``True`` draw a ``tqdm`` bar of the points when tqdm is installed;
    ``False`` nothing).

    Raises
    ------
    StudyError
        The store holds another study.
    """
    from dask.distributed import Client, LocalCluster, as_completed

    if progress not in (None, True, False) and not callable(progress):
        raise StudyError(
            f"progress: give a callable, True, False or None, not {progress!r}"
        )
    store = Path(store)
    _open_store(study, store)
    todo = [i for i in range(len(study.points.values)) if i not in done(store)]
    own = client is None
    if own:
        cluster = LocalCluster(
            n_workers=os.cpu_count() or 1,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
        )
        client = Client(cluster)
    try:
        if todo:
            # keys of this call's own (a stopped call's cancelled tasks and
            # data must not stand in for this one's)
            call = uuid.uuid4().hex[:8]
            shared = client.scatter(study, broadcast=True, hash=False)
            futures = client.map(
                run_point,
                [shared] * len(todo),
                todo,
                [str(store)] * len(todo),
                key=[f"ssm-point-{call}-{i}" for i in todo],
                retries=retries,
                pure=False,
            )
            failed = 0
            started = time.perf_counter()
            bar = _bar(progress, len(todo))
            if bar is not None:
                progress = bar
            try:
                for finished, future in enumerate(as_completed(futures), start=1):
                    record = future.result()
                    failed += record.get("error") is not None
                    if callable(progress):
                        left = len(todo) - finished
                        rate = (time.perf_counter() - started) / finished
                        progress(finished, failed, left, rate * left)
            except BaseException:
                # stopped (Ctrl-C, a failing callback): what is not running
                # yet is not started; the finished points stay in the store
                client.cancel(futures)
                raise
            finally:
                if bar is not None:
                    bar.close()
    finally:
        if own:
            client.close()
            cluster.close()
    return read(study, store)
