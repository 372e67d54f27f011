"""Whole plans from Python: the engine's pipeline on a model from arrays,
every analysis of a scene reachable as a dictionary."""

import numpy as np
import pytest
import ssm
from conftest import duffing
from ssm.errors import InputError
from test_answers import harmonic_balance

PLAN = {
    "ssm": {"order": 7},
    "coordinates": ["x"],
    "frc": {"epsilon": [0.002], "omega_range": [0.95, 1.05]},
    "reference": {"epsilon": [0.002], "harmonics": 5},
    "analyses": [{"name": "damping", "spec": {"rho_max": 0.2, "points": 11}}],
}


def test_the_full_system_reference_agrees_with_a_harmonic_balance_written_here():
    """Reference: the harmonic balance of ``test_answers`` (harmonics 1, 3,
    5, scipy's root finder; the engine's has harmonics 0 to 5, whose even
    ones vanish for the Duffing oscillator). At every tenth orbit of the
    engine's continuation the largest ``|x|`` agrees to 1e-8 of the peak.
    The forced response's error the run measures against it is the one the
    pytest comparison finds (about 1e-3, ``test_answers``)."""
    zeta, w, kappa, eps = 0.01, 1.0, 0.5, 0.002
    run = ssm.run(duffing(zeta, w, kappa), PLAN)
    orbits = run.table("reference_frc.csv")
    assert len(orbits) > 50
    omega, amp = orbits["omega"].to_numpy(), orbits["x_linf"].to_numpy()
    hb = np.array(
        [
            harmonic_balance(zeta, w, kappa, eps, om, a)
            for om, a in zip(omega[::10], amp[::10])
        ]
    )
    assert np.abs(amp[::10] - hb).max() < 1e-8 * amp.max()
    (measured,) = run.summary["accuracy"]["measured"]
    assert measured["against"] == "harmonic_balance"
    assert 5e-4 < measured["relative_error"] < 2e-3


def test_the_plan_reaches_the_registry_analyses():
    """Reference (closed form): the damping curve's ``zeta`` at ``rho = 0``
    is ``-Re lambda / Im lambda = zeta / sqrt(1 - zeta^2)`` of the linear
    mode, to 1e-10 (the 12 digits of ``damping.csv``)."""
    zeta = 0.01
    run = ssm.run(duffing(zeta=zeta), PLAN)
    damping = run.table("damping.csv")
    # damping.csv holds 12 significant digits
    assert np.isclose(
        damping["zeta"][0], zeta / np.sqrt(1 - zeta * zeta), rtol=1e-10, atol=0
    )
    assert "damping" in run.summary["analyses"]


@pytest.mark.parametrize(
    "plan, words",
    [
        ({"ssm": {"order": 5}, "frc": {"epsilon": [0.01], "pointz": 3}}, "pointz"),
        ({"ssm": {"order": 5}, "coordinates": ["nope"]}, "nope"),
        (
            {
                "ssm": {"order": 5},
                "coordinates": ["x"],
                "frc": {"epsilon": [0.01], "omega_range": [0.9, 1.1], "points": 10**12},
            },
            "forcing.points",
        ),
    ],
)
def test_bad_plans_are_input_errors(plan, words):
    with pytest.raises(InputError, match=words):
        ssm.run(duffing(), plan)


def test_a_run_without_the_file_asked_for_says_what_it_wrote():
    run = ssm.run(duffing(), {"ssm": {"order": 3}, "coordinates": ["x"]})
    with pytest.raises(InputError, match="spectrum.csv"):
        run.table("backbone.csv")
