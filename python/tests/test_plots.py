"""Figures for a paper: what each plot promises, checked on the drawn
artists (matplotlib's Agg backend)."""

import io

import matplotlib
import numpy as np
import pandas as pd
import pytest
import ssm
import ssm.plot
from conftest import duffing
from test_plan import PLAN

matplotlib.use("Agg")
import matplotlib.pyplot as plt

pytestmark = pytest.mark.filterwarnings("ignore::ssm.errors.SsmWarning")


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def drawn(ax):
    """Every data point of the axes' lines, in display coordinates."""
    ax.figure.canvas.draw()
    points = [ax.transData.transform(line.get_xydata()) for line in ax.get_lines()]
    return np.vstack([p for p in points if len(p)])


def check_paper_ready(ax, xword, yword):
    """Labels name the quantities; no tick label is a round-off number (a
    ``-5.6e-17`` for zero); the legend covers no drawn point."""
    assert xword in ax.get_xlabel() and yword in ax.get_ylabel()
    ax.figure.canvas.draw()
    for label in ax.get_xticklabels() + ax.get_yticklabels():
        text = label.get_text().replace("\u2212", "-")
        assert "e-1" not in text and "e-2" not in text, text
    legend = ax.get_legend()
    if legend is not None:
        box = legend.get_window_extent()
        inside = [box.contains(x, y) for x, y in drawn(ax)]
        assert not any(inside), f"{sum(inside)} points under the legend"


def test_a_backbone_draws_its_untrusted_part_differently():
    """The Duffing backbone to rho = 1.2 at O(3) leaves its accuracy target
    (1 %): the part beyond ``trusted_up_to`` is a dashed line of its own,
    starting where the solid one ends, and the error band is drawn."""
    s = ssm.compute_ssm(duffing(), [1], 3, progress=False)
    (curve,) = s.backbone(rho_max=1.2, points=61, outputs=["x"])
    assert curve.untrusted and curve.trusted_up_to is not None
    ax = ssm.plot.backbone([curve], "x")
    solid = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-"]
    dashed = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
    assert len(solid) == 1 and len(dashed) == 1
    x_solid, x_dashed = solid[0].get_xdata(), dashed[0].get_xdata()
    assert x_dashed[0] <= x_solid[-1] < x_dashed[-1]
    assert len(ax.collections) == 1  # the error band
    check_paper_ready(ax, "x", "frequency")


def test_a_forced_response_marks_stability_bifurcations_and_the_reference():
    """The Duffing FRC at eps = 0.01 has a bistable band: its unstable
    middle branch is dashed, its two folds are marked, and the full
    system's orbits of the plan's reference are drawn beneath as circles,
    filled where stable and open where unstable."""
    model = duffing()
    band = [0.95, 1.15]
    plan = {
        "ssm": {"order": 7},
        "coordinates": ["x"],
        "frc": {"epsilon": [0.01], "omega_range": band},
        "reference": {"epsilon": [0.01], "harmonics": 5},
    }
    run = ssm.run(model, plan, progress=False)
    s = ssm.compute_ssm(model, [1], 7, progress=False)
    frc = s.forced_response([0.01], band, points=400, outputs=["x"])
    folds = [b for c in frc.curves for b in c["bifurcations"] if b[0] == "SN"]
    assert len(folds) == 2
    reference = run.table("reference_frc.csv")
    ax = ssm.plot.forced_response(frc, "x", reference=reference)
    styles = {
        ln.get_linestyle() for ln in ax.get_lines() if ln.get_marker() in ("None", "")
    }
    assert styles == {"-", "--"}
    markers = [
        ln
        for ln in ax.get_lines()
        if ln.get_marker() == "o" and len(ln.get_xdata()) == 1
    ]
    assert len(markers) == 2
    full = [
        ln
        for ln in ax.get_lines()
        if ln.get_markeredgecolor() == "black" and len(ln.get_xdata()) > 1
    ]
    assert [ln.get_markerfacecolor() for ln in full] == ["0.7", "white"]
    assert sum(len(ln.get_xdata()) for ln in full) == len(reference)
    # beneath the reduced curves, which stay visible
    assert all(ln.get_zorder() < 3 for ln in full)
    check_paper_ready(ax, "Omega", "x")


def test_validation_keeps_full_and_reduced_apart():
    """The full system is thick and black, the reduced model thin, dashed
    and coloured; the error panel is logarithmic."""
    t = np.linspace(0, 10, 201)
    table = pd.DataFrame(
        {
            "t": t,
            "x_full": np.cos(t),
            "x_rom": np.cos(t) * (1 + 1e-3),
            "rel_error": np.full_like(t, 1e-3),
            "manifold_distance": np.full_like(t, 1e-5),
        }
    )
    fig = ssm.plot.validation(table)
    top, bottom = fig.axes
    full, rom = top.get_lines()
    assert (
        full.get_color() == "black" and full.get_linewidth() > 2 * rom.get_linewidth()
    )
    assert rom.get_linestyle() == "--" and rom.get_color() != "black"
    assert bottom.get_yscale() == "log"
    check_paper_ready(top, "", "x")


def test_damping_and_speed_against_error_draw_the_run_tables():
    """The damping curve of a run and a speed-against-error table are drawn
    with their labels; the figure saves as SVG."""
    run = ssm.run(duffing(), PLAN, progress=False)
    ax = ssm.plot.damping(run.table("damping.csv"), "x")
    check_paper_ready(ax, "x", "damping")
    report = pd.DataFrame(
        {
            "kind": ["rom", "rom", "full_transient"],
            "order": [3, 5, np.nan],
            "ssm_s": [1e-4, 2e-4, np.nan],
            "transient_s": [1e-3, 2e-3, 2e-2],
            "transient_error": [1e-1, 1e-2, np.nan],
        }
    )
    ax = ssm.plot.speed_against_error(report)
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    out = io.BytesIO()
    ax.figure.savefig(out, format="svg")
    assert out.getvalue().startswith(b"<?xml")


def test_pod_values_and_errors_draw_the_study_tables():
    """The POVs of a POD study on a log scale, the kept ones filled (two on
    a chain forced on two modes, ``test_pod``), and the reduced model's
    error over the training run; labels name the quantities, the legend is
    beside the axes."""
    from test_pod import chain

    M, K, phi = chain()
    model = ssm.from_arrays(
        M, K, rayleigh=(0.0, 0.01), fext=M @ phi[:, :2].sum(axis=1), outputs={"end": 19}
    )
    study = ssm.pod(
        model,
        train={"t_end": 50.0, "epsilon": 0.01, "omega": 0.2},
        step=0.05,
        outputs=["end"],
    )
    ax = ssm.plot.pod_values(study.table("pod_povs.csv"))
    assert ax.get_yscale() == "log"
    filled = [
        ln for ln in ax.get_lines() if ln.get_marker() == "o" and ln.get_mfc() != "none"
    ]
    assert sum(len(ln.get_xdata()) for ln in filled) == 2
    check_paper_ready(ax, "index", "POV")
    ax = ssm.plot.pod_errors(study.table("pod_case_1.csv"))
    assert ax.get_yscale() == "log" and len(ax.get_lines()) == 1
    check_paper_ready(ax, "time", "error")
