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
    """Each name is ``model.<parameter>`` or ``<plan section>.<key>`` (the
    engine's check, the one ``ssm-engine study`` makes)."""
    from ._ssm import study_check_parameter

    for name in names:
        try:
            study_check_parameter(str(name))
        except SsmError as e:
            raise StudyError(str(e)) from None


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
    """``n`` points drawn uniformly from the box ``ranges`` (parameter ->
    ``(low, high)``) as ``ssm-engine study`` draws a ``[sample]``: ChaCha8
    seeded with ``seed``, the parameters in the order of their names, ``n``
    draws each."""
    from ._ssm import study_sample

    _check_parameters(list(ranges))
    try:
        drawn = study_sample(
            [(str(k), float(lo), float(hi)) for k, (lo, hi) in ranges.items()],
            int(n),
            int(seed),
        )
    except (SsmError, OverflowError) as e:
        raise StudyError(str(e)) from None
    return Points(tuple(dict(p) for p in drawn))


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
    """The base plan (complete, with its defaults) with the point's plan
    values set (``section.key``), as ``ssm-engine study`` sets them: a
    number given for ``frc.epsilon`` or ``frc.orders`` becomes a list of
    one."""
    from ._analyses import spec_json
    from ._ssm import study_plan_at

    values = [[k, _plain(v)] for k, v in point.items()]
    return json.loads(study_plan_at(spec_json(plan), json.dumps(values)))


def figures(
    run: Any, point: Mapping[str, Any], backbone_at: Sequence[float] = ()
) -> dict[str, Any]:
    """A point's figures from its run, as ``ssm-engine study`` records
    them (one implementation, in the engine): per forced response curve
    (``O<k>_`` before the names when the curves have several orders) the
    first output's peak amplitude and its frequency (``peak_amplitude``,
    ``peak_omega``), the frequencies of its folds and branch points
    (``fold_omegas``, ``branch_point_omegas``), its error estimate and
    ``frc_untrusted``; per backbone curve its relative frequency shift
    ``omega(rho) / omega(0) - 1`` at each polar amplitude of
    ``backbone_at`` (``backbone_shift@<a>``, linear interpolation; NaN
    beyond the curve); the largest backbone estimate and the order.
    (:func:`run_point` adds the wall time, the warnings and any error.)
    Give other amplitudes with ``functools.partial(figures,
    backbone_at=[...])`` as a study's ``answers``."""
    from ._ssm import study_figures

    return dict(study_figures(list(run.files.items()), [float(a) for a in backbone_at]))


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


def _cell(v: Any) -> Any:
    """A record's value: lists and dictionaries as JSON text."""
    v = _plain(v)
    if isinstance(v, (list, dict)):
        # as the engine writes its lists (UTF-8, not escaped)
        return json.dumps(v, ensure_ascii=False)
    return v


def _write_record(store: Path, index: int, record: Mapping[str, Any]) -> None:
    """``record`` as point ``index``'s one-row Parquet file of ``store``,
    written under a temporary name and renamed by the engine's store (the
    layout ``ssm-engine study`` writes): a reader sees the whole record or
    none."""
    from ._ssm import study_write_record

    study_write_record(str(store), index, [(k, _cell(v)) for k, v in record.items()])


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
    _write_record(Path(store), index, record)
    return record


# -- the study, on a cluster ------------------------------------------------------


def _open_store(study: Study, store: Path) -> None:
    """Creates the store for ``study`` or checks that it holds ``study``
    (the engine's store: ``study.json`` written once even when several
    processes open the store at once)."""
    from ._ssm import study_open_store

    dims = None if study.points.dims is None else list(study.points.dims)
    try:
        study_open_store(
            str(store), study.fingerprint(), len(study.points.values), dims
        )
    except SsmError as e:
        raise StudyError(str(e)) from None


def done(store: str | Path) -> set[int]:
    """The points the store holds a record of."""
    folder = Path(store) / "points"
    if not folder.exists():
        return set()
    return {
        int(p.stem)
        for p in folder.glob("*.parquet")
        if p.stem.isdigit() and p.is_file() and not p.is_symlink()
    }


def read(store: str | Path) -> Any:
    """The records of ``store`` (written by :func:`run` or by ``ssm-engine
    study``) as a ``pandas.DataFrame`` (one row per point, in the points'
    order), or, for a grid, an ``xarray.Dataset`` with one dimension per
    grid parameter; lists (fold frequencies, warnings) come back as lists.
    A column whose records disagree on its type (text in one, numbers in
    another) holds Python objects."""
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq

    store = Path(store)
    meta = store / "study.json"
    if not meta.is_file():
        raise StudyError(f"store: {store} holds no study (no study.json)")
    dims = json.loads(meta.read_text()).get("dims")
    paths = [_record_path(store, i) for i in sorted(done(store))]
    if not paths:
        raise StudyError(f"store: {store} holds no finished point")
    tables = [pq.read_table(p) for p in paths]
    try:
        frame = pa.concat_tables(tables, promote_options="default").to_pandas()
    except (pa.ArrowInvalid, pa.ArrowTypeError):
        frame = pd.concat([t.to_pandas() for t in tables], ignore_index=True)
    frame = frame.sort_values("point").reset_index(drop=True)
    for column in frame.columns:
        values = frame[column]
        if (
            values.dtype == object
            and values.map(lambda v: isinstance(v, str) and v[:1] in "[{").all()
        ):
            frame[column] = values.map(json.loads)
    if dims is None:
        return frame
    dims = [f"param:{d}" for d in dims]
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
            _remove_orphans(store)
    finally:
        if own:
            client.close()
            cluster.close()
    return read(store)


def _remove_orphans(store: Path) -> None:
    """Removes the temporary files of records whose writer died mid-write
    (a worker killed while writing: Dask ran its point again elsewhere).
    Called once every point has finished, when no writer of this study is
    left."""
    points_dir = store / "points"
    for p in points_dir.glob(".*.tmp"):
        p.unlink(missing_ok=True)
