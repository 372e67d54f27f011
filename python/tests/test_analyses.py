"""Every analysis of the engine as a call on an SSM, its numbers as numpy
arrays, against references computed here."""

import warnings

import numpy as np
import pytest
import scipy.integrate
import ssm
from conftest import duffing
from ssm.errors import InputError, UntrustedAnswerWarning
from test_answers import harmonic_balance

ZETA, W, KAPPA = 0.01, 1.0, 0.5


def duffing_flow(t, z):
    """The Duffing oscillator of ``conftest.duffing`` as a first-order flow."""
    x, v = z
    return [v, -2 * ZETA * W * v - W * W * x - KAPPA * x**3]


@pytest.mark.parametrize("order, bound", [(3, 5e-2), (5, 3e-3), (7, 3e-4)])
def test_the_reduced_transient_follows_the_full_system_from_its_point_on_the_ssm(
    order, bound
):
    """Reference: the full Duffing oscillator integrated by scipy (DOP853,
    rtol 1e-12) from the state ``Ssm.state`` gives at ``rho = 0.3`` (``x``
    about 0.42, a backbone shift of 3 %). Over 30 periods the reduced
    transient's ``x(t)`` agrees with it within ``bound`` of the initial
    amplitude (measured: 2.1e-2, 1.3e-3, 9.9e-5 at O(3), O(5), O(7)), and
    its error estimate is within a factor of three of that error (measured
    ratios 2.0, 1.8, 1.7). The first sample is the state's ``x`` (both are
    ``W(p0)``); the polar amplitude decays at the linear rate ``zeta w``
    within 1e-3 (measured 1.1e-4 at O(7))."""
    s = ssm.compute_ssm(duffing(ZETA, W, KAPPA), [1], order)
    t_end = 30 * 2 * np.pi
    with warnings.catch_warnings():
        # O(3) is rightly untrusted at this amplitude
        warnings.simplefilter("ignore", UntrustedAnswerWarning)
        tr = s.transient([0.3], t_end, samples=1201, outputs=["x"])
    assert isinstance(tr, ssm.Transient) and tr.order == order
    assert tr.untrusted == (order == 3)
    z0 = s.state([0.3])
    assert z0.shape == (2,) and tr.outputs["x"][0] == pytest.approx(z0[0], 1e-14)
    full = scipy.integrate.solve_ivp(
        duffing_flow,
        (0.0, t_end),
        z0,
        method="DOP853",
        t_eval=tr.times,
        rtol=1e-12,
        atol=1e-14,
    )
    gap = np.abs(full.y[0] - tr.outputs["x"]).max() / abs(z0[0])
    assert gap < bound, gap
    assert gap / 3 < tr.error_estimate < 3 * gap, (gap, tr.error_estimate)
    assert tr.rho[0, 0] == 0.3
    if order == 7:
        linear = 0.3 * np.exp(-ZETA * W * t_end)
        assert tr.rho[-1, 0] == pytest.approx(linear, rel=1e-3)
    frame = tr.to_pandas()
    assert list(frame.columns) == ["t", "x", "rho_1", "theta_1"]


def test_the_reference_call_gives_orbits_their_stability_and_the_folds():
    """Reference: the harmonic balance of ``test_answers`` (harmonics 1, 3,
    5, scipy's root finder) at every fifth orbit of the full-system
    reference at eps = 0.01, past the folds: the largest ``|x|`` agrees to
    1e-8 of the peak. Stability by theory: of the three responses between
    the two folds, the middle one is the unstable saddle (every orbit
    between the folds on that part of the branch has a multiplier outside
    the unit circle, every other orbit none); at each fold the critical
    Floquet multiplier is +1 within 1e-6 (measured 4e-15), and the folds
    (measured at Omega = 1.04294 and 1.02848) are where the branch turns,
    within 2e-3."""
    s = ssm.compute_ssm(duffing(ZETA, W, KAPPA), [1], 5)
    ref = s.reference([0.01], (0.95, 1.12), harmonics=5, outputs=["x"])
    assert isinstance(ref, ssm.Reference) and ref.harmonics == 5
    table = ref.to_pandas()
    main = table[(table["continued"] == "omega") & (table["branch"] == 1)]
    assert len(main) > 50
    omega, amp = main["omega"].to_numpy(), main["x"].to_numpy()
    folds = [e for e in ref.events if e["kind"] == "SN"]
    assert len(folds) == 2, ref.events
    # near a fold two responses nearly coincide and the root finder, started
    # from an amplitude alone, may take either: those orbits are left out
    away = np.min([np.abs(omega - e["omega"]) for e in folds], axis=0) > 5e-3
    for om, a in zip(omega[away][::5], amp[away][::5]):
        assert abs(harmonic_balance(ZETA, W, KAPPA, 0.01, om, a) - a) < 1e-8 * amp.max()
    for e in folds:
        assert abs(e["multiplier"] - 1.0) < 1e-6, e
    lo, hi = sorted(e["omega"] for e in folds)
    # along the branch: up the resonance to the upper fold, back down the
    # saddle to the lower fold, on along the lower branch
    step = np.diff(omega)
    upper = int(np.argmax(step < 0))
    lower = upper + int(np.argmax(step[upper:] > 0))
    assert omega[upper] == pytest.approx(hi, abs=2e-3)
    assert omega[lower] == pytest.approx(lo, abs=2e-3)
    stable = main["stable"].to_numpy()
    inner = slice(upper + 2, lower - 1)
    assert np.all(stable[inner] == 0.0)
    assert np.all(stable[: upper - 1] == 1.0) and np.all(stable[lower + 2 :] == 1.0)
    assert np.all(main["max_multiplier"].to_numpy()[inner] > 1.0)


PLAN_SECTIONS = {
    "invariance": {"radii": [0.05, 0.2], "orders": [3, 5, 7]},
    "damping": {"rho_max": 0.2, "points": 11},
    "validation": {
        "transient": {"start": {"ssm": {"rho0": [0.2]}}, "t_end": 40.0},
    },
    "report": {},
}


def untimed(value):
    """``value`` without its wall-clock times (keys ``seconds``, ``*_s``,
    ``steps_per_s``), which differ from run to run."""
    if isinstance(value, dict):
        return {
            k: untimed(v)
            for k, v in value.items()
            if not (k == "seconds" or k.endswith("_s"))
        }
    if isinstance(value, list):
        return [untimed(v) for v in value]
    return value


@pytest.mark.parametrize("name", sorted(PLAN_SECTIONS))
def test_an_analysis_call_gives_what_the_whole_plan_gives(name):
    """A determinism check across two doors: the call on an SSM and the same
    section in a whole plan (``ssm.run``) give the same summary and the
    same tables, byte for byte."""
    model = duffing(ZETA, W, KAPPA)
    s = ssm.compute_ssm(model, [1], 7)
    if name == "report":
        alone = s.report(outputs=["x"])
    else:
        alone = s.analyze(name, outputs=["x"], **PLAN_SECTIONS[name])
    plan = {"ssm": {"order": 7}, "coordinates": ["x"]}
    if name == "damping":
        plan["analyses"] = [{"name": name, "spec": PLAN_SECTIONS[name]}]
    else:
        plan[name] = PLAN_SECTIONS[name]
    whole = ssm.run(model, plan)
    if name == "damping":
        summary = whole.summary["analyses"]["damping"]
    elif name == "invariance":
        summary = whole.summary["invariance_error"]
    else:
        summary = whole.summary[name]
    assert untimed(alone.summary) == untimed(summary)
    for f, data in alone.files.items():
        if f.endswith(".csv") and name != "report":
            assert whole.files[f] == data, f


def test_the_invariance_error_falls_with_the_order_and_grows_with_the_radius():
    """Reference: the convergence of the expansion: the residual of the
    invariance equation on the torus of radius 0.05 falls by more than a
    factor of 10 each two orders (O(3), O(5), O(7)) and grows with the
    radius at every order."""
    s = ssm.compute_ssm(duffing(ZETA, W, KAPPA), [1], 7)
    rows = s.invariance([0.05, 0.2], orders=[3, 5, 7]).summary
    err = {(r["order"], r["radius"]): r["error"] for r in rows}
    assert err[(5, 0.05)] < err[(3, 0.05)] / 10
    assert err[(7, 0.05)] < err[(5, 0.05)] / 10
    for o in (3, 5, 7):
        assert err[(o, 0.05)] < err[(o, 0.2)]


@pytest.mark.parametrize(
    "name, spec, words",
    [
        ("nonesuch", {}, "nonesuch"),
        ("transient", {"rho0": [0.1], "t_end": 1.0, "tend": 2}, "tend"),
        ("transient", {"rho0": [0.1], "t_end": 1.0, "order": 9}, "order 9"),
        ("transient", {"rho0": [0.1, 0.2], "t_end": 1.0}, "rho0"),
        ("transient", {"rho0": [0.1], "t_end": float("nan")}, "t_end: nan"),
        ("damping", {"rho_max": 0.2, "points": 10**13}, "points"),
        ("invariance", {"radii": [], "orders": [3]}, "radii"),
    ],
)
def test_bad_analysis_requests_are_input_errors(name, spec, words):
    s = ssm.compute_ssm(duffing(), [1], 5)
    with pytest.raises(InputError, match=words):
        s.analyze(name, outputs=["x"], **spec)


def test_state_refuses_a_point_of_the_wrong_size():
    s = ssm.compute_ssm(duffing(), [1], 5)
    with pytest.raises(InputError, match="master pair"):
        s.state([0.1, 0.2])
    with pytest.raises(InputError, match="order"):
        s.state([0.1], order=6)
