"""Figures of the answers, for a paper (matplotlib, an optional dependency).

Every function draws on ``ax`` (a new figure's axes when ``None``) and
returns the axes (or the figure, for several panels). Conventions: the
untrusted part of an answer (its error estimate above the tolerance) is drawn
dashed and paler, not only named in the legend; unstable branches are dashed,
stable ones solid; the full system is drawn in black with markers or thick
lines, the reduced model in colour; axes are labelled with the outputs'
names; the legend stands beside the axes, never over the data.

Example
-------
>>> import ssm, ssm.plot
>>> s = ssm.compute_ssm(model, [1], 7)                      # doctest: +SKIP
>>> ssm.plot.backbone(s.backbone(0.3, outputs=["x"]), "x")  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

# the largest relative error estimate drawn as a band
BAND_MAX = 0.25

# markers of the bifurcations a continuation locates
_MARKERS = {"SN": "o", "BP": "s", "PD": "D", "NS": "^", "HB": "v"}
_NAMES = {
    "SN": "fold",
    "BP": "branch point",
    "PD": "period doubling",
    "NS": "Neimark-Sacker",
    "HB": "Hopf",
}


def _axes(ax: Any) -> Any:
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, ax = plt.subplots(figsize=(7.6, 4.4), layout="constrained")
    return ax


def _finish(ax: Any, xlabel: str, ylabel: str) -> Any:
    """Labels, plain tick labels (no offset, no ``-5.6e-17`` for zero) and
    the legend beside the axes, never over the data."""
    from matplotlib.ticker import ScalarFormatter

    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "linear":
            fmt = ScalarFormatter(useOffset=False)
            fmt.set_powerlimits((-3, 4))
            axis.set_major_formatter(fmt)
    handles, _ = ax.get_legend_handles_labels()
    if handles:
        # beside the axes, never over the data (the figure's constrained
        # layout makes room for it)
        ax.legend(
            loc="upper left",
            bbox_to_anchor=(1.02, 1.0),
            borderaxespad=0.0,
            frameon=False,
        )
    return ax


def _colors(n: int) -> list[Any]:
    import matplotlib.pyplot as plt

    cycle = plt.rcParams["axes.prop_cycle"].by_key().get("color", ["C0"])
    return [cycle[k % len(cycle)] for k in range(n)]


def backbone(
    curves: Sequence[Any],
    output: str | None = None,
    ax: Any = None,
    tolerance: float | None = None,
    label: str = "",
    colors: Sequence[Any] | None = None,
) -> Any:
    """Backbone curves (:meth:`ssm.Ssm.backbone`): the frequency against the
    amplitude of ``output`` (the polar amplitude ``rho`` when ``None``), one
    colour per order (or per entry of ``colors``), with the band
    ``omega (1 +- e)`` of the error estimate ``e``. The part beyond the
    curve's trusted range (``trusted_up_to``, or where ``e`` exceeds
    ``tolerance``) is dashed and paler. ``label`` prefixes the legend's
    entries (e.g. ``"from data"`` beside ``"model"`` on the same axes)."""
    ax = _axes(ax)
    colors = list(colors) if colors is not None else _colors(len(curves))
    for curve, color in zip(curves, colors):
        x = curve.rho if output is None else curve.amplitudes[output]
        omega, e = curve.omega, np.asarray(curve.error_estimate, dtype=float)
        bad = np.zeros(len(x), dtype=bool)
        if curve.trusted_up_to is not None:
            bad |= curve.rho > curve.trusted_up_to
        elif curve.untrusted:
            bad |= True
        if tolerance is not None:
            bad |= np.nan_to_num(e, nan=0.0) > tolerance
        good = ~bad
        # the two parts share their boundary point, so the curve is unbroken
        cut = int(np.argmax(bad)) if bad.any() else len(x)
        label_k = f"{label} O({curve.order})".strip()
        ax.plot(
            x[: cut + 1][good[: cut + 1]],
            omega[: cut + 1][good[: cut + 1]],
            color=color,
            lw=1.8,
            label=label_k,
        )
        if bad.any():
            lo = max(cut - 1, 0)
            ax.plot(
                x[lo:],
                omega[lo:],
                color=color,
                lw=1.4,
                ls="--",
                alpha=0.6,
                label=f"{label_k}, estimate above tolerance",
            )
        _band(ax, x, omega, e, color)
    xlabel = "polar amplitude rho" if output is None else f"amplitude of {output}"
    return _finish(ax, xlabel, "frequency omega (rad/s)")


def _band(ax: Any, x: np.ndarray, y: np.ndarray, e: np.ndarray, color: Any) -> None:
    """The band ``y (1 +- e)`` of a relative error estimate ``e``, where it
    is still a small error (beyond :data:`BAND_MAX` the curve is dashed, and
    a band would only stretch the axes)."""
    shown = np.isfinite(e) & (e <= BAND_MAX)
    if shown.any():
        ax.fill_between(
            x[shown],
            (y * (1 - e))[shown],
            (y * (1 + e))[shown],
            color=color,
            alpha=0.15,
            lw=0,
        )


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """The ``[start, stop)`` runs of equal values of ``mask``."""
    if len(mask) == 0:
        return []
    edges = np.flatnonzero(np.diff(mask.astype(int))) + 1
    starts = np.concatenate([[0], edges])
    stops = np.concatenate([edges, [len(mask)]])
    return list(zip(starts.tolist(), stops.tolist()))


def forced_response(
    frc: Any,
    output: str,
    ax: Any = None,
    reference: Any = None,
    steady_states: Any = None,
) -> Any:
    """Forced response curves (:meth:`ssm.Ssm.forced_response`): the
    amplitude of ``output`` against the forcing frequency, one colour per
    curve (order and forcing amplitude), stable parts solid, unstable parts
    dashed, bifurcations marked. ``reference``: the full system's periodic
    orbits (``reference_frc.csv`` of :func:`ssm.run` as a DataFrame: black,
    filled where stable, open where unstable); ``steady_states``: a
    DataFrame with ``omega`` and the output's amplitude (black crosses)."""
    ax = _axes(ax)
    cols = frc.columns
    amp = frc.amplitudes[output]
    keys = sorted({(int(o), float(e)) for o, e in zip(cols["order"], cols["epsilon"])})
    seen_kind: set[str] = set()
    for k, ((order, eps), color) in enumerate(zip(keys, _colors(len(keys)))):
        # earlier curves wider, so that coinciding ones all stay visible
        width = 1.2 + 0.9 * (len(keys) - 1 - k)
        on = (cols["order"] == order) & (cols["epsilon"] == eps)
        curve = next(
            (c for c in frc.curves if c["order"] == order and c["epsilon"] == eps), {}
        )
        label = f"O({order}), eps = {eps:g}"
        if curve.get("untrusted"):
            label += ", untrusted"
        labelled = False
        for b in np.unique(cols["branch"][on]):
            rows = np.flatnonzero(on & (cols["branch"] == b))
            stable = np.asarray(cols["stable"][rows], dtype=bool)
            for start, stop in _runs(stable):
                # overlap by one point so that the branch is unbroken
                seg = rows[max(start - 1, 0) : stop]
                ax.plot(
                    cols["omega"][seg],
                    amp[seg],
                    color=color,
                    ls="-" if stable[start] else "--",
                    lw=width if stable[start] else 0.75 * width,
                    alpha=0.6 if curve.get("untrusted") else 1.0,
                    zorder=3,
                    label=None if labelled else label,
                )
                labelled = True
        for kind, omega, branch in curve.get("bifurcations", []):
            rows = np.flatnonzero(on & (cols["branch"] == branch))
            if len(rows) == 0:
                continue
            at = rows[np.argmin(np.abs(cols["omega"][rows] - omega))]
            ax.plot(
                [omega],
                [amp[at]],
                ls="none",
                marker=_MARKERS.get(kind, "*"),
                mfc="white",
                mec="black",
                ms=7,
                zorder=5,
                label=None if kind in seen_kind else _NAMES.get(kind, kind),
            )
            seen_kind.add(kind)
    if reference is not None:
        column = f"{output}_linf" if f"{output}_linf" in reference else output
        om, a = reference["omega"].to_numpy(), reference[column].to_numpy()
        flag = reference["stable"].to_numpy(dtype=float)
        # larger markers beneath the reduced curves, which stay visible;
        # orbits whose stability was not computed are drawn as stable ones
        # under a label of their own
        groups = [
            (flag == 1, "0.7", "full system, stable"),
            (flag == 0, "white", "full system, unstable"),
            (np.isnan(flag), "0.7", "full system"),
        ]
        for rows, face, name in groups:
            if rows.any():
                ax.plot(
                    om[rows],
                    a[rows],
                    ls="none",
                    marker="o",
                    ms=4.5,
                    mfc=face,
                    mec="black",
                    mew=0.5,
                    zorder=2,
                    label=name,
                )
    if steady_states is not None:
        column = f"{output}_linf" if f"{output}_linf" in steady_states else output
        ax.plot(
            steady_states["omega"],
            steady_states[column],
            ls="none",
            marker="x",
            ms=7,
            color="black",
            zorder=4,
            label="full system, steady states",
        )
    return _finish(ax, "forcing frequency Omega (rad/s)", f"amplitude of {output}")


def validation(table: Any, outputs: Sequence[str] | None = None) -> Any:
    """The full system against the reduced model (``validation.csv`` of
    :func:`ssm.run` as a DataFrame): one panel per output (the full system
    thick and black, the reduced model thin, dashed and coloured, so both
    show where they coincide) and a panel of the relative error (log
    scale). Returns the figure."""
    import matplotlib.pyplot as plt

    if outputs is None:
        outputs = [
            c[: -len("_full")]
            for c in table.columns
            if c.endswith("_full") and f"{c[:-5]}_rom" in table
        ]
    n = len(outputs)
    fig, axes = plt.subplots(
        n + 1, 1, sharex=True, figsize=(6.4, 2.0 * (n + 1) + 0.6), layout="constrained"
    )
    t = table["t"].to_numpy()
    for ax, name, color in zip(axes, outputs, _colors(n)):
        ax.plot(t, table[f"{name}_full"], color="black", lw=2.6, label="full system")
        ax.plot(
            t, table[f"{name}_rom"], color=color, lw=1.2, ls="--", label="reduced model"
        )
        _finish(ax, "", name)
    err = axes[-1]
    err.semilogy(t, table["rel_error"], color="black", lw=1.2, label="relative error")
    if "manifold_distance" in table:
        err.semilogy(
            t,
            table["manifold_distance"],
            color="C3",
            lw=1.0,
            ls=":",
            label="distance to the SSM",
        )
    _finish(err, "time t (s)", "error")
    return fig


def damping(table: Any, output: str | None = None, ax: Any = None) -> Any:
    """The damping curve (``damping.csv`` of :func:`ssm.run` as a
    DataFrame): the damping ratio ``zeta`` against the amplitude of
    ``output`` (``rho`` when ``None``), one colour per order, with the band
    ``zeta (1 +- e)`` of the error estimate where one is given (up to 25 %)."""
    ax = _axes(ax)
    orders = sorted(set(table["order"]))
    for order, color in zip(orders, _colors(len(orders))):
        rows = table[table["order"] == order]
        x = rows["rho" if output is None else output].to_numpy()
        zeta = rows["zeta"].to_numpy()
        ax.plot(x, zeta, color=color, lw=1.8, label=f"O({order})")
        if "error_estimate" in rows:
            _band(ax, x, zeta, rows["error_estimate"].to_numpy(dtype=float), color)
    xlabel = "polar amplitude rho" if output is None else f"amplitude of {output}"
    return _finish(ax, xlabel, "damping ratio zeta")


def speed_against_error(table: Any, ax: Any = None) -> Any:
    """The speed-against-error report (``report.csv`` as a DataFrame): for
    each answer measured against the full system (the transient, the forced
    response), the reduced models' time (the SSM and the answer) against
    their measured error, log-log, one point per order; the full system's
    time of the same answer as a horizontal black line."""
    ax = _axes(ax)
    kind = table["kind"].astype(str).to_numpy()
    rom = kind == "rom"
    ssm_s = table["ssm_s"].fillna(0.0).to_numpy()
    answers = [a for a in ("transient", "frc") if f"{a}_error" in table]
    for answer, marker, color in zip(answers, "os", _colors(len(answers))):
        err = table[f"{answer}_error"].to_numpy(dtype=float)
        time = ssm_s + table[f"{answer}_s"].to_numpy(dtype=float)
        ok = rom & np.isfinite(err) & (err > 0) & np.isfinite(time)
        if not ok.any():
            continue
        name = "forced response" if answer == "frc" else answer
        ax.loglog(
            err[ok],
            time[ok],
            ls="-",
            marker=marker,
            color=color,
            label=f"reduced, {name}",
        )
        for o, x, y in zip(table["order"].to_numpy()[ok], err[ok], time[ok]):
            ax.annotate(
                f"O({int(o)})",
                (x, y),
                textcoords="offset points",
                xytext=(4, 4),
                fontsize=8,
            )
        full = table[kind == f"full_{answer}"][f"{answer}_s"].to_numpy(dtype=float)
        for t in full[np.isfinite(full)]:
            ax.axhline(
                t,
                color="black",
                lw=1.2,
                ls="-" if answer == "transient" else "-.",
                label=f"full system, {name}",
            )
    return _finish(ax, "measured relative error", "time (s)")


def pod_values(table: Any, ax: Any = None) -> Any:
    """The proper orthogonal values (``pod_povs.csv`` of :func:`ssm.pod` as
    a DataFrame): each kind's values relative to its largest, log scale,
    against their index; the values a reduced model keeps filled, the
    others open (values at round-off are drawn at 1e-17)."""
    ax = _axes(ax)
    kinds = list(dict.fromkeys(table["kind"].astype(str)))
    for kind, color in zip(kinds, _colors(len(kinds))):
        rows = table[table["kind"].astype(str) == kind]
        index = rows["index"].to_numpy()
        value = np.maximum(rows["relative"].to_numpy(dtype=float), 1e-17)
        kept = rows["kept_by"].notna().to_numpy()
        ax.semilogy(index, value, color=color, lw=1.0, label=kind)
        ax.semilogy(index[kept], value[kept], "o", color=color, label=f"{kind}, kept")
        ax.semilogy(index[~kept], value[~kept], "o", mfc="none", color=color)
    return _finish(ax, "index", "POV / largest of its kind")


def pod_errors(table: Any, ax: Any = None) -> Any:
    """The error of each reduced model over a POD run (``pod_case_<k>.csv``
    as a DataFrame: its ``error@<model>`` columns), log scale against time;
    exact zeros are drawn at 1e-17."""
    ax = _axes(ax)
    columns = [c for c in table.columns if c.startswith("error@")]
    for column, color in zip(columns, _colors(len(columns))):
        err = np.maximum(table[column].to_numpy(dtype=float), 1e-17)
        ax.semilogy(table["t"], err, color=color, label=column.split("@", 1)[1])
    return _finish(ax, "time t", "relative error of the outputs")
