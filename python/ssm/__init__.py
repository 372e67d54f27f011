"""Nonlinear model reduction of mechanical systems on spectral submanifolds.

A model comes from arrays (:func:`from_arrays`), a model folder
(:func:`from_files`), a plugin (:func:`from_plugin`), a scene file
(:func:`from_scene`) or sampled signals (:func:`identify`);
:func:`compute_ssm` computes its spectral submanifold (SSM) over chosen
master mode pairs, and the SSM answers, each with its error estimate:
:meth:`Ssm.backbone`, :meth:`Ssm.forced_response`, and every other analysis
of the engine (:meth:`Ssm.analyze`: the invariance error, the reduced
transient, the full system's periodic orbits with their Floquet multipliers,
validation, the speed-against-error report, sampled runs, the damping
curve). :func:`pod` runs the POD study, :func:`run` a whole plan and
:func:`run_scene` a scene file; :mod:`ssm.plot` draws the results. The
computations run in the Rust engine with the GIL released; Ctrl-C stops
them.

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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _analyses, errors
from ._analyses import Analysis, Reference, Transient
from ._models import from_arrays, from_files, from_plugin, from_scene, identify
from ._progress import Progress as _Progress
from ._progress import warn as _warn
from ._progress import warn_engine as _warn_engine
from ._ssm import Model, __version__, run_plan
from ._ssm import Ssm as _Ssm
from ._ssm import run_scene as _run_scene
from ._ssm import state_on_ssm as _state_on_ssm
from .errors import InputError, UntrustedAnswerWarning

__all__ = [
    "Analysis",
    "Backbone",
    "ForcedResponse",
    "Model",
    "Reference",
    "Run",
    "Ssm",
    "Transient",
    "__version__",
    "compute_ssm",
    "errors",
    "from_arrays",
    "from_files",
    "from_plugin",
    "from_scene",
    "identify",
    "pod",
    "run",
    "run_scene",
]


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

    def __init__(self, inner: _Ssm, resonance_tol: float) -> None:
        self._inner = inner
        self._resonance_tol = resonance_tol

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

    def state(
        self,
        rho: Sequence[float],
        theta: Sequence[float] | None = None,
        order: int | None = None,
    ) -> np.ndarray:
        """The model's state ``z = W(p)`` on the SSM at the reduced point of
        polar amplitudes ``rho`` and phases ``theta`` (one each per master
        pair; default phases 0), the expansion truncated at ``order``
        (default the SSM's): for a mechanical model ``(x, x')``, then the
        multipliers of its constraints. A full-system run started there
        stays on the SSM (up to the expansion's error)."""
        return _state_on_ssm(
            self._inner,
            [float(r) for r in np.atleast_1d(rho)],
            None if theta is None else [float(t) for t in np.atleast_1d(theta)],
            None if order is None else int(order),
        )

    def analyze(
        self,
        name: str,
        outputs: Sequence[str] = (),
        tolerance: float = 0.01,
        progress: Any = None,
        **spec: Any,
    ) -> Analysis:
        """Runs the engine's analysis ``name`` on this SSM, as a scene's run
        does: ``spec`` holds the keys of its scene table (``docs/scene.md``;
        the same defaults and checks), ``outputs`` the outputs its answers
        are read at, ``tolerance`` the accuracy target its estimates are held
        to. The engine's cost gate refuses what would not fit before anything
        runs. Names: ``invariance``, ``transient``, ``reference``,
        ``validation``, ``report``, ``simulate``, ``damping`` (and
        ``backbone``, ``frc``; see :meth:`backbone` and
        :meth:`forced_response` for their typed results).

        Returns
        -------
        Analysis
            Its ``summary`` (what ``summary.json`` holds of it), ``files``
            (CSV and SVG by name; ``.table()`` reads a CSV), ``warnings``,
            ``estimates`` and ``measured`` errors; a :class:`Transient` or
            :class:`Reference` with numpy arrays for those two.

        Raises
        ------
        ssm.errors.InputError
            An unknown name or key, a value the spec's check refuses, an
            order above the SSM's, an unknown output, a request over the
            machine's limits.
        ssm.errors.AnalysisError
            The analysis failed (its message).
        """
        return _analyses.analyze(self._inner, name, spec, outputs, tolerance, progress)

    def invariance(
        self,
        radii: Sequence[float],
        orders: Sequence[int] | None = None,
        n_alpha: int = 10,
        n_theta: int = 30,
        progress: Any = None,
    ) -> Analysis:
        """The invariance error of the SSM on tori of the polar radii
        ``radii``, at each order of ``orders`` (default the SSM's): the
        residual of the invariance equation relative to the vector field,
        sampled at ``n_alpha`` x ``n_theta`` points a torus. ``summary``
        holds a row per order and radius."""
        orders = [self.order] if orders is None else [int(o) for o in orders]
        spec = {"radii": list(radii), "orders": orders}
        spec.update(n_alpha=int(n_alpha), n_theta=int(n_theta))
        return _analyses.analyze(self._inner, "invariance", spec, (), 0.01, progress)

    def transient(
        self,
        rho0: Sequence[float],
        t_end: float,
        theta0: Sequence[float] | None = None,
        samples: int = 1001,
        order: int | None = None,
        rtol: float = 1e-9,
        outputs: Sequence[str] = (),
        tolerance: float = 0.01,
        progress: Any = None,
    ) -> Transient:
        """The free decay of the reduced model from the polar amplitudes
        ``rho0`` (phases ``theta0``, default 0) to ``t_end``, lifted to the
        ``outputs`` at ``samples`` times, with its error estimate (an
        untrusted one warns with
        :class:`ssm.errors.UntrustedAnswerWarning`)."""
        spec = {
            "rho0": [float(r) for r in np.atleast_1d(rho0)],
            "theta0": None if theta0 is None else list(np.atleast_1d(theta0)),
            "t_end": float(t_end),
            "samples": int(samples),
            "order": order,
            "rtol": float(rtol),
        }
        return _analyses.analyze(
            self._inner, "transient", spec, outputs, tolerance, progress
        )

    def reference(
        self,
        epsilon: Sequence[float],
        omega_range: tuple[float, float],
        harmonics: int = 9,
        outputs: Sequence[str] = (),
        progress: Any = None,
        **options: Any,
    ) -> Reference:
        """The full system's periodic orbits under ``eps fext cos(Omega
        t)`` for each amplitude of ``epsilon`` over ``omega_range``, by
        harmonic balance with ``harmonics`` harmonics and pseudo-arclength
        continuation, with their Floquet multipliers and the bifurcations on
        the branches: the reference the reduced forced response is judged
        against. ``options``: the other keys of ``[reference]`` (``step``,
        ``tol``, ``max_steps``, ``stability``, ``period_doubling``,
        ``amplitude_at``, ``amplitude_range``, ``start``)."""
        spec = {
            "epsilon": [float(e) for e in np.atleast_1d(epsilon)],
            "omega_range": [float(omega_range[0]), float(omega_range[1])],
            "harmonics": int(harmonics),
        }
        spec.update(options)
        return _analyses.analyze(
            self._inner, "reference", spec, outputs, 0.01, progress
        )

    def validation(
        self, outputs: Sequence[str] = (), progress: Any = None, **spec: Any
    ) -> Analysis:
        """The reduced answers against the full system (``[validate]``:
        ``transient`` runs from points on the SSM, ``steady_state`` orbits at
        given frequencies), the errors measured in ``measured``."""
        return _analyses.analyze(
            self._inner, "validation", spec, outputs, 0.01, progress
        )

    def report(
        self,
        orders: Sequence[int] | None = None,
        forcing: Mapping[str, Any] | None = None,
        rtol: float = 1e-8,
        outputs: Sequence[str] = (),
        progress: Any = None,
    ) -> Analysis:
        """The speed-against-error report (``[report]``): the reduced models
        of ``orders`` (default the odd orders from 3 to the SSM's) against
        the full system, run time and error each; ``forcing`` (the keys of
        :meth:`forced_response`, e.g. ``{"epsilon": [0.01], "omega_range":
        [0.9, 1.1]}``) adds the forced response at each order; ``rtol`` is
        the integrators' relative tolerance. The SSMs of the lower orders
        are computed with this SSM's ``resonance_tol``."""
        spec = {
            "orders": None if orders is None else [int(o) for o in orders],
            "forcing": forcing,
            "rtol": float(rtol),
            "resonance_tol": self._resonance_tol,
        }
        return _analyses.analyze(self._inner, "report", spec, outputs, 0.01, progress)

    def simulate(
        self, outputs: Sequence[str] = (), progress: Any = None, **spec: Any
    ) -> Analysis:
        """Sampled runs of the full system (``[simulate]``: ``period``,
        ``samples``, ``runs``, ``noise``, ...), its tables in ``files``."""
        return _analyses.analyze(self._inner, "simulate", spec, outputs, 0.01, progress)

    def damping(
        self,
        outputs: Sequence[str] = (),
        tolerance: float = 0.01,
        progress: Any = None,
        **spec: Any,
    ) -> Analysis:
        """The amplitude-dependent damping and frequency of the SSM's free
        oscillation (``[analysis.damping]``: ``rho_max``, ``points``,
        ``orders``), a table per order, its error estimates held to
        ``tolerance``."""
        return _analyses.analyze(
            self._inner, "damping", spec, outputs, tolerance, progress
        )

    def __repr__(self) -> str:
        """The order, the master pairs and the model's name."""
        return repr(self._inner)


@dataclass
class Run:
    """What a plan's run wrote: ``summary.json`` as a dictionary and every
    file (CSV tables, SVG plots) by name; ``engine_seconds`` is the wall
    time of the engine's own call (the rest of the call's time is this
    layer's)."""

    summary: dict[str, Any]
    files: dict[str, bytes]
    engine_seconds: float | None = None

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


def _run_of(files: Sequence[tuple[str, bytes]], seconds: float) -> Run:
    """The :class:`Run` of the files a run wrote and the engine's seconds,
    its warnings issued (pointing at the caller of :func:`run` or
    :func:`run_scene`)."""
    import json

    files = dict(files)
    summary = json.loads(files["summary.json"])
    _warn_engine(summary.get("warnings", []), depth=2)
    return Run(summary=summary, files=files, engine_seconds=seconds)


def run(model: Model, plan: Mapping[str, Any], progress: Any = None) -> Run:
    """Runs a whole plan on ``model``: the engine's pipeline, as a scene's run
    does, within the machine's limits (the engine's cost gate refuses what
    would not fit). ``plan`` holds the sections of a scene as a dictionary
    (the engine's ``Plan`` in JSON: ``ssm``, ``coordinates``, ``backbone``,
    ``invariance``, ``transient``, ``frc``, ``validation``, ``reference``,
    ``report``, ``simulate``, ``analyses``; see ``docs/python.md``). The
    run's warnings are issued as :class:`ssm.errors.SsmWarning`, an
    untrusted answer's as :class:`ssm.errors.UntrustedAnswerWarning`.
    ``progress``: see :func:`compute_ssm`."""
    with _Progress(progress) as callback:
        files, seconds = run_plan(model, _analyses.spec_json(plan), callback)
    return _run_of(files, seconds)


def pod(
    model: Model,
    train: Mapping[str, Any],
    step: float,
    tests: Sequence[Mapping[str, Any]] = (),
    truncations: Mapping[str, Any] | None = None,
    outputs: Sequence[str] = (),
    progress: Any = None,
    **options: Any,
) -> Run:
    """The POD study of ``model`` (Stadlmayr, Witteveen & Steiner 2017): a
    training run of the full model (HHT-alpha with the fixed ``step``), its
    proper orthogonal decomposition, a Galerkin model per truncation with
    the generalized constraint reduction, and every model run on the
    training load and on ``tests``, each with its seconds and its error
    against the full run at ``outputs``.

    Parameters
    ----------
    train, tests : mapping
        Loads ``eps fext cos(Omega t)``: ``t_end``, ``epsilon`` and
        ``omega`` (default 0: a free run), ``start`` (``[(state name,
        value)]``, default rest).
    step : float
        The fixed time step of every run.
    truncations : mapping, optional
        ``{"energy": [1e-6, ...]}`` (energy fractions left out) or
        ``{"drop": [6, ...]}`` (drops of the normalized POVs, in decades); one
        model at a drop of 6 decades by default.
    options
        The other keys of ``[pod]`` (``rank_tol``, ``jacobian_samples``,
        ``hht_alpha``, ``ssm_pairs``, ``ssm_order``).

    Returns
    -------
    Run
        ``summary["pod"]`` (the POVs, the models, their errors and
        seconds) and the files ``pod_comparison.csv``, ``pod_povs.csv``,
        ``pod_report.md``, ...
    """
    spec: dict[str, Any] = {"train": dict(train), "step": float(step)}
    spec["tests"] = [dict(t) for t in tests]
    if truncations is not None:
        spec["truncations"] = dict(truncations)
    spec.update(options)
    return run(model, {"coordinates": [str(o) for o in outputs], "pod": spec}, progress)


def run_scene(path: str, plugins: Sequence[str] = (), progress: Any = None) -> Run:
    """Runs the scene file ``path`` as ``ssm-engine SCENE.toml`` does (its
    model, its plan, the engine's cost gate; the POD study included) and
    returns what the run writes, in memory: nothing is written to disk.
    ``progress``: see :func:`compute_ssm`."""
    with _Progress(progress) as callback:
        files, seconds = _run_scene(str(path), [str(p) for p in plugins], callback)
    return _run_of(files, seconds)


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
    return Ssm(inner, float(resonance_tol))
