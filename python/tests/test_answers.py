"""Answers of the reduced model against closed forms and a harmonic
balance written here."""

import numpy as np
import pandas as pd
import pytest
import scipy.optimize
import ssm
from conftest import duffing


@pytest.mark.parametrize(
    "zeta, w, kappa", [(0.01, 1.0, 0.5), (0.05, 2.3, -0.8), (0.2, 0.7, 3.0)]
)
def test_duffing_backbone_is_the_closed_form_normal_form(zeta, w, kappa):
    """Reference: the O(3) normal form of the Duffing oscillator with the
    unit-normalized master eigenvector, ``omega(rho) = w_d + 3 kappa rho^2 /
    (2 w_d (1 + w^2))`` (derived in the suite's
    ``ssm_autonomous::duffing_cubic_backbone_coefficient_matches_closed_form``);
    tolerance 1e-12 relative."""
    model = duffing(zeta, w, kappa)
    s = ssm.compute_ssm(model, [1], 3)
    curve = s.backbone(0.2, points=11, outputs=["x"])[0]
    wd = w * np.sqrt(1.0 - zeta * zeta)
    expected = wd + 3.0 * kappa * curve.rho**2 / (2.0 * wd * (1.0 + w * w))
    assert np.allclose(curve.omega, expected, rtol=1e-12, atol=0.0)
    assert curve.amplitudes["x"][0] == 0.0 and np.all(
        np.diff(curve.amplitudes["x"]) > 0
    )


def harmonic_balance(
    zeta, w, kappa, eps, omega, guess, harmonics=(1, 3, 5), samples=64
):
    """The periodic response of the Duffing oscillator to ``eps cos(Omega
    t)`` by harmonic balance (odd harmonics, alternating frequency-time for
    the cubic force), solved by ``scipy.optimize.root`` from the amplitude
    ``guess``; its largest ``|x(t)|`` over the period."""
    t = 2 * np.pi * np.arange(samples) / samples
    h = np.array(harmonics)
    cos, sin = np.cos(np.outer(h, t)), np.sin(np.outer(h, t))

    def residual(c):
        a, b = c[: len(h)], c[len(h) :]
        x = a @ cos + b @ sin
        xd = (-a * h * omega) @ sin + (b * h * omega) @ cos
        xdd = (-a * (h * omega) ** 2) @ cos + (-b * (h * omega) ** 2) @ sin
        r = xdd + 2 * zeta * w * xd + w * w * x + kappa * x**3 - eps * np.cos(t)
        return np.concatenate([cos @ r, sin @ r]) * 2 / samples

    # the start: the first harmonic of amplitude ``guess`` with the phase
    # its one-harmonic balance gives, so that where several responses
    # coexist the root finder takes the one of that amplitude
    phase = np.arctan2(
        2 * zeta * w * omega * guess,
        (w * w - omega * omega + 0.75 * kappa * guess**2) * guess,
    )
    c0 = np.zeros(2 * len(h))
    c0[0], c0[len(h)] = guess * np.cos(phase), guess * np.sin(phase)
    sol = scipy.optimize.root(residual, c0, tol=1e-13)
    assert np.abs(residual(sol.x)).max() < 1e-12 * eps, sol.message
    a, b = sol.x[: len(h)], sol.x[len(h) :]

    def minus_abs(tau):
        return -abs(a @ np.cos(h * tau) + b @ np.sin(h * tau))

    # the largest |x| over the period: a grid, then the maximum refined
    # between the grid's neighbours of its best point
    fine = np.linspace(0, 2 * np.pi, 2001)
    k = int(np.argmax([-minus_abs(tau) for tau in fine]))
    step = fine[1] - fine[0]
    best = scipy.optimize.minimize_scalar(
        minus_abs,
        bounds=(fine[k] - step, fine[k] + step),
        method="bounded",
        options={"xatol": 1e-12},
    )
    return -best.fun


def test_duffing_forced_response_agrees_with_a_harmonic_balance():
    """Reference: a harmonic balance written here (harmonics 1, 3, 5,
    scipy's root finder) at every fifth point of the O(7) forced response at
    eps = 0.002 (peak near 0.1, below the first fold, so one response per
    frequency). The largest ``|x(t)|`` agrees within 2e-3 of the peak
    amplitude (measured: 1.05e-3, near the peak), and the curve's own error
    estimate (9.3e-4) names that error within a factor of two."""
    zeta, w, kappa, eps = 0.01, 1.0, 0.5, 0.002
    s = ssm.compute_ssm(duffing(zeta, w, kappa), [1], 7)
    frc = s.forced_response([eps], (0.9, 1.1), points=200, outputs=["x"])
    omega, a = frc.columns["omega"], frc.amplitudes["x"]
    assert len(a) > 50 and a.max() > 0.09
    hb = np.array(
        [
            harmonic_balance(zeta, w, kappa, eps, om, g)
            for om, g in zip(omega[::5], a[::5])
        ]
    )
    error = np.abs(a[::5] - hb).max() / hb.max()
    curve = frc.curves[0]
    assert error < 2e-3, error
    assert not curve["untrusted"]
    assert 0.5 * error < curve["error_estimate"] < 2.0 * error, (error, curve)


def test_results_become_tables(duffing_model):
    s = ssm.compute_ssm(duffing_model, [1], 5)
    table = s.backbone(0.3, points=7, outputs=["x"])[0].to_pandas()
    assert isinstance(table, pd.DataFrame)
    assert list(table.columns) == ["rho", "omega", "x", "error_estimate"]
    assert len(table) == 7
