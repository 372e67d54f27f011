"""Models: from numpy and scipy arrays, model folders, plugins, scene
files, and identified from sampled signals by a reducer."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ._ssm import (
    Model,
    model_from_plugin,
    model_from_scene,
    model_from_signals,
)
from .errors import InputError


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


def _indices(arg: str, a: Any) -> np.ndarray:
    """Indices as they are when ``int32`` or ``int64`` (borrowed), else
    converted to ``int64``; a non-integer dtype is refused."""
    a = np.asarray(a)
    if a.dtype.kind not in "iu":
        raise InputError(f"{arg}: indices of dtype {a.dtype}; give integers")
    if a.dtype in (np.int32, np.int64):
        return a
    return a.astype(np.int64)


def _values(arg: str, a: Any) -> np.ndarray:
    """Values as they are when ``float64`` (borrowed, any strides), else
    converted from another floating-point dtype; integer, boolean and
    complex dtypes are refused."""
    a = np.asarray(a)
    if a.dtype.kind == "c":
        raise InputError(f"{arg}: complex values ({a.dtype}); the model is real")
    if a.dtype.kind != "f":
        raise InputError(f"{arg}: dtype {a.dtype}; give floating-point values")
    return a if a.dtype == np.float64 else a.astype(np.float64)


def _matrix(arg: str, a: Any, shape: tuple[int, int]) -> Any:
    """The dense or ``scipy.sparse`` matrix ``a`` of shape ``shape`` as the
    engine reads it: a dense array, ``(format, indptr, indices, data)`` of
    CSR and CSC, or ``(rows, cols, values)`` of COO, the arrays' buffers
    handed over as they are (no copy for ``float64`` values and ``int32``
    or ``int64`` indices; other sparse formats pass through CSR)."""
    if hasattr(a, "tocoo"):
        if tuple(a.shape) != tuple(shape):
            raise InputError(f"{arg}: shape {tuple(a.shape)}, expected {tuple(shape)}")
        if a.format not in ("csr", "csc", "coo"):
            a = a.tocsr()
        data = _values(arg, a.data)
        if a.format == "coo":
            return (_indices(arg, a.row), _indices(arg, a.col), data)
        return (a.format, _indices(arg, a.indptr), _indices(arg, a.indices), data)
    dense = np.asarray(a)
    if dense.ndim != 2:
        raise InputError(f"{arg}: a matrix is needed, found {dense.ndim} dimension(s)")
    if tuple(dense.shape) != tuple(shape):
        raise InputError(f"{arg}: shape {tuple(dense.shape)}, expected {tuple(shape)}")
    return _values(arg, dense)


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
        constraints = (int(g.shape[0]), _matrix("G", G, (g.shape[0], n)))
    load = None
    if fext is not None:
        load = _float_array("fext", fext)
        if load.shape != (n,):
            raise InputError(f"fext: shape {load.shape}, expected ({n},)")
    return Model.from_coo(
        name,
        n,
        _matrix("M", M, (n, n)),
        _matrix("K", K, (n, n)),
        damping=None if C is None else _matrix("C", C, (n, n)),
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
