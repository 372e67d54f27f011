"""The engine's analyses run on an SSM one at a time (``Ssm.analyze`` and the
named calls ``Ssm.invariance``, ``Ssm.transient``, ``Ssm.reference``,
``Ssm.validation``, ``Ssm.report``, ``Ssm.simulate``, ``Ssm.damping``): each
spec takes the keys of its scene table, with the scene's defaults and
checks, and passes the engine's cost gate before it runs."""

from __future__ import annotations

import io
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._progress import Progress, warn_engine
from ._ssm import analyze as _analyze
from .errors import InputError


@dataclass
class Analysis:
    """The results of one analysis: ``summary`` (what ``summary.json``
    holds of it), ``files`` (its CSV tables and SVG plots by name, as a
    scene's run writes them), ``warnings``, the error ``estimates`` of its
    answers and the errors it ``measured`` against the full system."""

    name: str
    summary: Any
    files: dict[str, bytes]
    warnings: list[str]
    estimates: list[dict[str, Any]]
    measured: list[dict[str, Any]]

    def table(self, name: str | None = None) -> Any:
        """The CSV file ``name`` (default: the only one) as a
        ``pandas.DataFrame``."""
        import pandas as pd

        tables = sorted(f for f in self.files if f.endswith(".csv"))
        if name is None:
            if len(tables) != 1:
                raise InputError(f"name: give one of the tables {tables}")
            name = tables[0]
        if name not in self.files:
            raise InputError(
                f"name: the analysis wrote no '{name}'; it wrote {sorted(self.files)}"
            )
        return pd.read_csv(io.BytesIO(self.files[name]))


@dataclass
class Transient(Analysis):
    """A transient of the reduced model lifted to the outputs: ``times``,
    each output's values ``outputs[name]``, the polar coordinates ``rho``
    and ``theta`` of the master pairs (a column per pair), the integrator's
    ``steps``, the ``error_estimate`` (relative; ``None`` for maps) and
    ``untrusted``."""

    order: int = 0
    times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outputs: dict[str, np.ndarray] = field(default_factory=dict)
    rho: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    theta: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    steps: int = 0
    error_estimate: float | None = None
    untrusted: bool = False

    def to_pandas(self) -> Any:
        """The samples as a ``pandas.DataFrame``: ``t``, the outputs, and
        ``rho_j``, ``theta_j`` per master pair."""
        import pandas as pd

        columns: dict[str, Any] = {"t": self.times}
        columns.update(self.outputs)
        for j in range(self.rho.shape[1]):
            columns[f"rho_{j + 1}"] = self.rho[:, j]
            columns[f"theta_{j + 1}"] = self.theta[:, j]
        return pd.DataFrame(columns)


@dataclass
class Reference(Analysis):
    """The full system's periodic orbits by harmonic balance: one row per
    orbit of ``columns`` (``continued`` in ``"omega"`` or ``"epsilon"``,
    ``omega``, ``epsilon``, ``stable`` (1, 0, or NaN where no multipliers
    were computed), ``branch``, ``period_multiple``, ``max_multiplier`` (the
    largest Floquet multiplier's modulus), ``tail`` (the relative amplitude
    of the last harmonic)), each output's amplitude ``amplitudes[name]``
    (``max_t |y(t)|``), and the bifurcations located on the branches
    (``events``: kind, omega, epsilon, branch, the critical multiplier)."""

    harmonics: int = 0
    columns: dict[str, np.ndarray] = field(default_factory=dict)
    amplitudes: dict[str, np.ndarray] = field(default_factory=dict)
    events: list[dict[str, Any]] = field(default_factory=list)

    def to_pandas(self) -> Any:
        """The orbits as a ``pandas.DataFrame``."""
        import pandas as pd

        data: dict[str, Any] = dict(self.columns)
        data.update(self.amplitudes)
        return pd.DataFrame(data)


def spec_json(spec: Mapping[str, Any]) -> str:
    """The spec as JSON: numpy scalars and arrays as plain numbers, ``None``
    values left out (the engine's default); a value JSON cannot hold (NaN,
    an infinity, an object) is an error naming its key."""

    def plain(v: Any, key: str) -> Any:
        if isinstance(v, np.ndarray):
            v = v.tolist()
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, Mapping):
            return {
                str(k): plain(x, f"{key}.{k}" if key else str(k))
                for k, x in v.items()
                if x is not None
            }
        if isinstance(v, (list, tuple)):
            return [plain(x, key) for x in v]
        if isinstance(v, float) and not np.isfinite(v):
            raise InputError(f"{key}: {v} is not finite")
        if v is not None and not isinstance(v, (bool, int, float, str)):
            raise InputError(f"{key}: {type(v).__name__} is not a number or text")
        return v

    return json.dumps(plain(spec, ""))


def analyze(
    inner: Any,
    name: str,
    spec: Mapping[str, Any],
    outputs: Sequence[str],
    tolerance: float,
    progress: Any,
) -> Analysis:
    """Runs the analysis ``name`` on the SSM ``inner`` (see
    :meth:`ssm.Ssm.analyze`)."""
    with Progress(progress) as callback:
        raw = _analyze(
            inner,
            str(name),
            spec_json(spec),
            [str(o) for o in outputs],
            float(tolerance),
            callback,
        )
    base = {
        "name": raw["name"],
        "summary": json.loads(raw["summary"]),
        "files": dict(raw["files"]),
        "warnings": list(raw["warnings"]),
        "estimates": list(raw["estimates"]),
        "measured": list(raw["measured"]),
    }
    warn_engine(base["warnings"], depth=2)
    arrays = raw.get("arrays")
    names = [str(o) for o in outputs]
    if raw["name"] == "transient" and arrays is not None:
        values = arrays["outputs"]
        return Transient(
            **base,
            order=arrays["order"],
            times=arrays["times"],
            outputs={n: values[:, k] for k, n in enumerate(names)},
            rho=arrays["rho"],
            theta=arrays["theta"],
            steps=arrays["steps"],
            error_estimate=arrays["error_estimate"],
            untrusted=arrays["untrusted"],
        )
    if raw["name"] == "reference" and arrays is not None:
        amps = arrays["amplitudes"]
        columns = {
            k: arrays[k]
            for k in (
                "omega",
                "epsilon",
                "stable",
                "branch",
                "period_multiple",
                "max_multiplier",
                "tail",
            )
        }
        columns["continued"] = np.array(arrays["continued"], dtype=object)
        return Reference(
            **base,
            harmonics=arrays["harmonics"],
            columns=columns,
            amplitudes={n: amps[:, k] for k, n in enumerate(arrays["outputs"])},
            events=list(arrays["events"]),
        )
    return Analysis(**base)
