"""Nonlinear model reduction of mechanical systems on spectral submanifolds.

A model comes from arrays (:func:`from_arrays`) or from a model folder
(:func:`from_files`); :func:`compute_ssm` computes its spectral submanifold
(SSM) over chosen master mode pairs, and the SSM answers with error
estimates: :meth:`Ssm.backbone` and :meth:`Ssm.forced_response`. The
computations run in the Rust engine with the GIL released.

Example
-------
>>> import numpy as np, ssm
>>> model = ssm.from_arrays(
...     M=np.eye(1), K=np.eye(1), C=0.02 * np.eye(1),
...     f3=(np.array([[0, 0, 0, 0]]), np.array([0.5])),
...     fext=np.ones(1), outputs={"x": 0},
... )
>>> s = ssm.compute_ssm(model, master_pairs=[1], order=5)
>>> curve = s.backbone(rho_max=0.3, outputs=["x"])[0]
>>> round(float(curve.omega[0]), 6)
0.99995
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import errors
from ._ssm import (
    Model,
    __version__,
    model_from_plugin,
    model_from_scene,
    model_from_signals,
    run_plan,
)
from ._ssm import Ssm as _Ssm
from ._ssm import run_scene as _run_scene
from .errors import InputError, SsmWarning, UntrustedAnswerWarning

__all__ = [
    "Backbone",
    "ForcedResponse",
    "Model",
    "Run",
    "Ssm",
    "__version__",
    "compute_ssm",
    "errors",
    "from_arrays",
    "from_files",
    "from_plugin",
    "from_scene",
    "identify",
    "run",
    "run_scene",
]


def _float_array(arg: str, a: Any) -> np.ndarray:
    """``a`` as float64 values, refusing integer, boolean and complex dtypes."""
    a = np.asarray(a)
    if a.dtype.kind == "c":
        raise InputError(f"{arg}: complex values ({a.dtype}); the model is real")
    if a.dtype.kind != "f":
        raise InputError(f"{arg}: dtype {a.dtype}; give floating-point values")
    return np.ascontiguousarray(a, dtype=np.float64)


def _index_array(arg: str, a: Any) -> np.ndarray:
    """``a`` as int64 indices, refusing non-integer dtypes."""
    a = np.asarray(a)
    if a.dtype.kind not in "iu":
        raise InputError(f"{arg}: indices of dtype {a.dtype}; give integers")
    return np.ascontiguousarray(a, dtype=np.int64)


def _coo(arg: str, a: Any, shape: tuple[int, int]) -> tuple[np.ndarray, ...]:
    """The coordinates ``(rows, cols, values)`` of the dense or
    ``scipy.sparse`` matrix ``a`` of shape ``shape``."""
    if hasattr(a, "tocoo"):
        if a.dtype.kind != "f":
            _float_array(arg, np.zeros(0, dtype=a.dtype))
        coo = a.tocoo()
        got = coo.shape
        rows, cols, vals = coo.row, coo.col, coo.data
    else:
        dense = np.asarray(a)
        got = dense.shape
        if dense.ndim != 2:
            raise InputError(
                f"{arg}: a matrix is needed, found {dense.ndim} dimension(s)"
            )
        dense = _float_array(arg, dense)
        rows, cols = np.nonzero(dense)
        vals = dense[rows, cols]
    if tuple(got) != tuple(shape):
        raise InputError(f"{arg}: shape {tuple(got)}, expected {tuple(shape)}")
    return (
        _index_array(arg, rows),
        _index_array(arg, cols),
        _float_array(arg, vals),
    )


def _tensor(arg: str, t: Any, degree: int) -> tuple[np.ndarray, np.ndarray] | None:
    """A force tensor ``(indices, values)``: indices of shape
    ``(k, degree + 1)``, 0-based."""
    if t is None:
        return None
    try:
        idx, vals = t
    except (TypeError, ValueError):
        raise InputError(f"{arg}: give (indices, values)") from None
    idx = _index_array(arg, idx)
    if idx.ndim != 2 or idx.shape[1] != degree + 1:
        raise InputError(
            f"{arg}: indices of shape {idx.shape}; expected (k, {degree + 1})"
        )
    return idx, _float_array(arg, vals)


def _outputs(
    outputs: Mapping[str, Any] | None,
) -> list[tuple[str, list[tuple[int, float]]]]:
    """Named outputs: a displacement index, or weights ``{index: weight}``."""
    named = []
    for name, spec in (outputs or {}).items():
        if isinstance(spec, (int, np.integer)):
            weights = [(int(spec), 1.0)]
        elif isinstance(spec, Mapping):
            weights = [(int(i), float(w)) for i, w in spec.items()]
        else:
            weights = [(int(i), float(w)) for i, w in spec]
        if any(i < 0 for i, _ in weights):
            raise InputError(f"outputs: '{name}' weighs a negative index")
        named.append((str(name), weights))
    return named


def from_arrays(
    M: Any,
    K: Any,
    C: Any = None,
    *,
    rayleigh: tuple[float, float] | None = None,
    f2: Any = None,
    f3: Any = None,
    G: Any = None,
    g2: Any = None,
    g3: Any = None,
    fext: Any = None,
    outputs: Mapping[str, Any] | None = None,
    name: str = "model",
) -> Model:
    """The model ``M x'' + C x' + K x + f2(x) + f3(x) = eps fext cos(Omega t)``
    with constraints ``G x + g2(x) + g3(x) = 0``.

    Parameters
    ----------
    M, K, C : (n, n) arrays, dense or ``scipy.sparse``
        Mass (symmetric, every degree of freedom with mass unless a
        constraint fixes it), stiffness and damping; floating-point.
    rayleigh : (alpha, beta), optional
        ``C = alpha M + beta K`` (instead of ``C``).
    f2, f3 : (indices, values), optional
        Quadratic and cubic internal forces: row ``(i, j, k)`` of the
        ``(m, 3)`` indices adds ``value x_j x_k`` to ``f_i``; ``(i, j, k, l)``
        adds ``value x_j x_k x_l``. Indices are 0-based.
    G : (n_c, n) array, optional
        Linear constraint Jacobian; ``g2``, ``g3`` its nonlinear terms as
        ``f2``, ``f3`` (rows index constraints).
    fext : (n,) array, optional
        Load shape of the harmonic forcing.
    outputs : mapping, optional
        Named outputs: a displacement index, or ``{index: weight}``.
    name : str
        The model's name.

    Raises
    ------
    ssm.errors.InputError
        A wrong shape, dtype, value or index (the message names the argument).
    ssm.errors.ModelError
        An inconsistent model (e.g. a massless degree of freedom).
    """
    m = np.asarray(M) if not hasattr(M, "tocoo") else M
    if m.ndim != 2 or m.shape[0] != m.shape[1]:
        raise InputError(f"M: a square matrix is needed, found shape {m.shape}")
    n = int(m.shape[0])
    if n == 0:
        raise InputError("M: the model has no degree of freedom (shape (0, 0))")
    constraints = None
    if G is not None:
        g = np.asarray(G) if not hasattr(G, "tocoo") else G
        if g.ndim != 2:
            raise InputError(f"G: a matrix is needed, found {g.ndim} dimension(s)")
        constraints = (int(g.shape[0]), _coo("G", G, (g.shape[0], n)))
    load = None
    if fext is not None:
        load = _float_array("fext", fext)
        if load.shape != (n,):
            raise InputError(f"fext: shape {load.shape}, expected ({n},)")
    return Model.from_coo(
        name,
        n,
        _coo("M", M, (n, n)),
        _coo("K", K, (n, n)),
        damping=None if C is None else _coo("C", C, (n, n)),
        rayleigh=None if rayleigh is None else (float(rayleigh[0]), float(rayleigh[1])),
        f2=_tensor("f2", f2, 2),
        f3=_tensor("f3", f3, 3),
        constraints=constraints,
        g2=_tensor("g2", g2, 2),
        g3=_tensor("g3", g3, 3),
        fext=load,
        outputs=_outputs(outputs),
    )


def from_files(folder: str, rayleigh: tuple[float, float] | None = None) -> Model:
    """The model of a folder of files (``M.mtx``, ``K.mtx``, ``f3.coo``, ...;
    see ``docs/models.md``; the files' indices are 1-based)."""
    return Model.from_files(str(folder), rayleigh)


def from_plugin(plugin: str, model: str = "", **params: Any) -> Model:
    """The model ``model`` (default: the plugin's first) of the plugin
    library ``plugin``: a name found on ``SSM_PLUGIN_PATH`` or a path to its
    ``.so``; ``params`` are its parameters (``ssm-engine plugins`` lists
    them, with their defaults). A plugin that fails or panics raises
    :class:`ssm.errors.ModelError` with its message."""
    return model_from_plugin(str(plugin), model, params)


class _Tqdm:
    """A progress callback drawing a ``tqdm`` bar (made at the first call,
    shown after half a second so that short calls draw nothing)."""

    def __init__(self) -> None:
        self._bar: Any = None

    def __call__(self, stage: str, detail: str) -> None:
        if self._bar is None:
            try:  # a widget in a notebook, where ipywidgets is installed
                import ipywidgets  # noqa: F401
                from tqdm.auto import tqdm
            except ImportError:
                from tqdm import tqdm

            self._bar = tqdm(
                total=None,
                bar_format="{desc} [{elapsed}]",
                delay=0.5,
                leave=False,
            )
        # the engine's details name their stage
        self._bar.set_description_str(detail or stage, refresh=False)
        self._bar.update(0)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


class _Progress:
    """The progress callback of a call: ``progress`` when it is callable
    (it takes the stage and the detail, two strings, at most ten times a
    second), a ``tqdm`` bar when ``progress`` is true or ``None`` and tqdm is
    installed, nothing otherwise."""

    def __init__(self, progress: Any) -> None:
        self.callback: Any = None
        self._bar: _Tqdm | None = None
        if callable(progress):
            self.callback = progress
        elif progress is None or progress is True:
            try:
                import tqdm  # noqa: F401
            except ImportError:
                if progress is True:
                    raise InputError("progress: tqdm is not installed") from None
            else:
                self._bar = _Tqdm()
                self.callback = self._bar
        elif progress is not False:
            raise InputError(
                f"progress: give a callable, True, False or None, not {progress!r}"
            )

    def __enter__(self) -> Any:
        return self.callback

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.close()


def from_scene(path: str, plugins: Sequence[str] = ()) -> Model:
    """The model of the scene file ``path``: its ``[model]`` (a plugin's or a
    folder's) or the model its ``[reduce]`` makes (with the reducer's
    ``diagnostics``). Plugins are found as by ``ssm-engine``: ``plugins``
    (paths), ``SSM_PLUGIN_PATH``."""
    return model_from_scene(str(path), [str(p) for p in plugins])


def identify(
    signals: Any,
    period: float,
    names: Sequence[str] | None = None,
    reducer: str = "nar",
    plugin: str | None = None,
    **params: Any,
) -> Model:
    """The model a reducer identifies from sampled signals: by default the
    nonlinear autoregressive map of Szalai, Ehrhardt & Haller (2017), fitted
    by the NAR identifier built into the package (its parameters, e.g.
    ``nu``, ``order``, ``weighting``, as keyword arguments; ``ssm-engine
    plugins`` lists them); ``plugin`` (a name or a ``.so`` path) takes the
    reducer of a plugin instead.

    Parameters
    ----------
    signals : array or list of arrays
        One array per trajectory: ``(samples,)`` for one observable or
        ``(samples, observables)``, floating-point, finite, uniformly
        sampled from ``t = 0``.
    period : float
        The sampling period ``T``.
    names : list of str, optional
        The observables' names (the identified model's outputs); default
        ``y1, y2, ...``.

    Returns
    -------
    Model
        The identified model (a map with period ``T``); its ``diagnostics``
        hold what the reducer reported (e.g. ``frequencies`` and
        ``damping_ratios`` of the identified linear part).

    Raises
    ------
    ssm.errors.InputError
        No signals, a wrong shape or dtype, a non-finite sample or period, an
        unknown reducer (the message names the argument).
    ssm.errors.ModelError
        The reducer could not identify a model (its message).
    """
    if isinstance(signals, np.ndarray) or not isinstance(signals, Sequence):
        signals = [signals]
    if len(signals) == 0:
        raise InputError("signals: no trajectory given")
    arrays = []
    for k, a in enumerate(signals):
        arg = f"signals[{k}]"
        a = _float_array(arg, a)
        if a.ndim == 1:
            a = a[:, None]
        if a.ndim != 2:
            raise InputError(
                f"{arg}: shape {a.shape}; give (samples,) or (samples, observables)"
            )
        if a.shape[0] < 2 or a.shape[1] == 0:
            raise InputError(
                f"{arg}: shape {a.shape}; at least two samples of one observable"
            )
        if not np.isfinite(a).all():
            bad = np.argwhere(~np.isfinite(a))[0]
            raise InputError(
                f"{arg}: a non-finite sample at {tuple(int(i) for i in bad)}"
            )
        if arrays and a.shape[1] != arrays[0].shape[1]:
            raise InputError(
                f"{arg}: {a.shape[1]} observable(s), signals[0] has {arrays[0].shape[1]}"
            )
        arrays.append(np.ascontiguousarray(a))
    width = arrays[0].shape[1]
    if names is None:
        names = [f"y{j + 1}" for j in range(width)]
    names = [str(n) for n in names]
    if len(names) != width:
        raise InputError(f"names: {len(names)} name(s) for {width} observable(s)")
    period = float(period)
    if not (np.isfinite(period) and period > 0):
        raise InputError(f"period: {period} is not a positive finite sampling period")
    return model_from_signals(
        None if plugin is None else str(plugin),
        str(reducer),
        arrays,
        period,
        names,
        params,
    )


def _warn(messages: Sequence[str], category: type = SsmWarning) -> None:
    for m in messages:
        warnings.warn(m, category, stacklevel=3)


@dataclass
class Backbone:
    """A backbone curve: the frequency ``omega`` of the free oscillation on
    the SSM against its polar amplitude ``rho`` and the outputs' amplitudes,
    each point with its error estimate (NaN where none is made)."""

    order: int
    rho: np.ndarray
    omega: np.ndarray
    amplitudes: dict[str, np.ndarray]
    error_estimate: np.ndarray
    curve_error_estimate: float | None
    untrusted: bool
    trusted_up_to: float | None

    def to_pandas(self) -> Any:
        """The curve as a ``pandas.DataFrame`` (pandas is optional)."""
        import pandas as pd

        columns = {"rho": self.rho, "omega": self.omega}
        columns.update(self.amplitudes)
        columns["error_estimate"] = self.error_estimate
        return pd.DataFrame(columns)


@dataclass
class ForcedResponse:
    """Forced response curves: one row per point (order, epsilon, omega,
    branch, stability, polar amplitude, outputs' amplitudes), and per curve
    its error estimate, ``untrusted`` flag and bifurcations."""

    columns: dict[str, np.ndarray]
    amplitudes: dict[str, np.ndarray]
    curves: list[dict[str, Any]] = field(default_factory=list)

    def to_pandas(self) -> Any:
        """The points as a ``pandas.DataFrame`` (pandas is optional)."""
        import pandas as pd

        data = dict(self.columns)
        data.update(self.amplitudes)
        return pd.DataFrame(data)


class Ssm:
    """The SSM of a model over its master pairs (see :func:`compute_ssm`)."""

    def __init__(self, inner: _Ssm) -> None:
        self._inner = inner

    @property
    def order(self) -> int:
        """The expansion order."""
        return self._inner.order

    @property
    def master_eigenvalues(self) -> np.ndarray:
        """The master eigenvalues."""
        return self._inner.master_eigenvalues

    @property
    def w(self) -> np.ndarray:
        """The coefficients of ``W``: a row per multi-index, a column per state."""
        return self._inner.w

    def backbone(
        self,
        rho_max: float,
        points: int = 101,
        orders: Sequence[int] | None = None,
        outputs: Sequence[str] = (),
        tolerance: float = 0.01,
        progress: Any = None,
    ) -> list[Backbone]:
        """Backbone curves of one master pair up to the polar amplitude
        ``rho_max``, one per order of ``orders`` (default: the SSM's); an
        untrusted curve (estimate above ``tolerance``) warns with
        :class:`ssm.errors.UntrustedAnswerWarning`. ``progress``: see
        :func:`compute_ssm`."""
        with _Progress(progress) as callback:
            raw = self._inner.backbone(
                float(rho_max),
                int(points),
                None if orders is None else [int(o) for o in orders],
                [str(o) for o in outputs],
                float(tolerance),
                callback,
            )
        curves = []
        for c in raw:
            amps = {name: c["amplitudes"][:, k] for k, name in enumerate(c["outputs"])}
            curve = Backbone(
                order=c["order"],
                rho=c["rho"],
                omega=c["omega"],
                amplitudes=amps,
                error_estimate=c["error_estimate"],
                curve_error_estimate=c["curve_error_estimate"],
                untrusted=c["untrusted"],
                trusted_up_to=c["trusted_up_to"],
            )
            if curve.untrusted:
                _warn(
                    [
                        f"backbone O({curve.order}): the estimated error exceeds the "
                        f"accuracy target {tolerance:g}"
                        + (
                            f" beyond rho = {curve.trusted_up_to:.4g}"
                            if curve.trusted_up_to is not None
                            else ""
                        )
                    ],
                    UntrustedAnswerWarning,
                )
            curves.append(curve)
        return curves

    def forced_response(
        self,
        epsilon: Sequence[float],
        omega_range: tuple[float, float],
        points: int = 200,
        orders: Sequence[int] | None = None,
        outputs: Sequence[str] = (),
        tolerance: float = 0.01,
        progress: Any = None,
    ) -> ForcedResponse:
        """Forced response curves of the reduced model to
        ``eps fext cos(Omega t)``, one per amplitude of ``epsilon`` (and
        order of ``orders``) over ``omega_range``. ``progress``: see
        :func:`compute_ssm`."""
        eps = [float(e) for e in np.atleast_1d(epsilon)]
        with _Progress(progress) as callback:
            raw = self._inner.forced_response(
                eps,
                (float(omega_range[0]), float(omega_range[1])),
                int(points),
                None if orders is None else [int(o) for o in orders],
                [str(o) for o in outputs],
                float(tolerance),
                callback,
            )
        _warn(raw["warnings"], UntrustedAnswerWarning)
        columns = {
            k: raw[k] for k in ("order", "epsilon", "omega", "branch", "stable", "rho")
        }
        amps = {name: raw["amplitudes"][:, k] for k, name in enumerate(raw["outputs"])}
        return ForcedResponse(
            columns=columns, amplitudes=amps, curves=list(raw["curves"])
        )

    def __repr__(self) -> str:
        return repr(self._inner)


@dataclass
class Run:
    """What a plan's run wrote: ``summary.json`` as a dictionary and every
    file (CSV tables, SVG plots) by name."""

    summary: dict[str, Any]
    files: dict[str, bytes]

    def table(self, name: str) -> Any:
        """The CSV file ``name`` (e.g. ``"reference_frc.csv"``) as a
        ``pandas.DataFrame``."""
        import io

        import pandas as pd

        if name not in self.files:
            raise InputError(
                f"name: the run wrote no '{name}'; it wrote {sorted(self.files)}"
            )
        return pd.read_csv(io.BytesIO(self.files[name]))

    def forced_response(self) -> ForcedResponse:
        """The run's forced response curves (``frc.csv`` and the curves and
        bifurcations of ``summary.json``) as a :class:`ForcedResponse`, as
        :meth:`Ssm.forced_response` returns them (for :mod:`ssm.plot`)."""
        table = self.table("frc.csv")
        frc = self.summary.get("frc") or {}
        columns = {
            "order": table["order"].to_numpy(),
            "epsilon": table["epsilon"].to_numpy(),
            "omega": table["omega"].to_numpy(),
            "branch": table["branch"].to_numpy(),
            "stable": table["stable"].to_numpy().astype(bool),
            "rho": table["rho_1"].to_numpy() if "rho_1" in table else None,
        }
        amplitudes = {
            c[: -len("_linf")]: table[c].to_numpy()
            for c in table.columns
            if c.endswith("_linf")
        }
        curves = []
        for c in frc.get("curves", []):
            bifurcations = [
                (b["kind"], b["omega"], b["branch"])
                for b in frc.get("bifurcations", [])
                if b["order"] == c["order"] and b["epsilon"] == c["epsilon"]
            ]
            curves.append(
                {
                    "order": c["order"],
                    "epsilon": c["epsilon"],
                    "error_estimate": c.get("error_estimate"),
                    "untrusted": c.get("untrusted", False),
                    "bifurcations": bifurcations,
                }
            )
        return ForcedResponse(columns=columns, amplitudes=amplitudes, curves=curves)


def run(model: Model, plan: Mapping[str, Any], progress: Any = None) -> Run:
    """Runs a whole plan on ``model``: the engine's pipeline, as a scene's run
    does, within the machine's limits (the engine's cost gate refuses what
    would not fit). ``plan`` holds the sections of a scene as a dictionary
    (the engine's ``Plan`` in JSON: ``ssm``, ``coordinates``, ``backbone``,
    ``invariance``, ``transient``, ``frc``, ``validation``, ``reference``,
    ``report``, ``simulate``, ``analyses``; see ``docs/python.md``). The
    run's warnings are issued as :class:`ssm.errors.SsmWarning`.
    ``progress``: see :func:`compute_ssm`."""
    import json

    with _Progress(progress) as callback:
        files = dict(run_plan(model, json.dumps(plan), callback))
    summary = json.loads(files["summary.json"])
    _warn(summary.get("warnings", []))
    return Run(summary=summary, files=files)


def run_scene(path: str, plugins: Sequence[str] = (), progress: Any = None) -> Run:
    """Runs the scene file ``path`` as ``ssm-engine SCENE.toml`` does (its
    model, its plan, the engine's cost gate; the POD study included) and
    returns what the run writes, in memory: nothing is written to disk.
    ``progress``: see :func:`compute_ssm`."""
    import json

    with _Progress(progress) as callback:
        files = dict(_run_scene(str(path), [str(p) for p in plugins], callback))
    summary = json.loads(files["summary.json"])
    _warn(summary.get("warnings", []))
    return Run(summary=summary, files=files)


def compute_ssm(
    model: Model,
    master_pairs: Sequence[int] = (1,),
    order: int = 5,
    resonance_tol: float = 0.02,
    normalization: str = "unit",
    progress: Any = None,
) -> Ssm:
    """The SSM of ``model`` over ``master_pairs`` (1-based underdamped pairs,
    slowest first) to ``order``: the spectrum, the master modes and the
    non-resonance checks first (their findings warn with
    :class:`ssm.errors.SsmWarning`).

    Every computing call runs without the GIL (other Python threads run
    meanwhile) and stops within about a second at Ctrl-C, raising
    ``KeyboardInterrupt`` and returning nothing. ``progress`` is a callable
    taking the stage and where it is (two strings; called at most ten and
    at least four times a second while the work runs), ``True`` for a
    ``tqdm`` bar, ``False`` for none; ``None`` (the default) draws a
    ``tqdm`` bar when tqdm is installed."""
    with _Progress(progress) as callback:
        inner = _Ssm.compute(
            model,
            [int(p) for p in master_pairs],
            int(order),
            float(resonance_tol),
            str(normalization),
            callback,
        )
    _warn(inner.warnings)
    return Ssm(inner)
