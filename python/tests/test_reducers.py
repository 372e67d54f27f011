"""Models identified from signals: the NAR identifier built into the
package, fed numpy arrays made here with scipy."""

import numpy as np
import pytest
import ssm
from scipy.integrate import solve_ivp
from ssm.errors import InputError, ModelError

# the modified Shaw-Pierre oscillator, Szalai, Ehrhardt & Haller (2017),
# eq. (9.1), with the paper's values (Sect. 9a)
C, K0, KAPPA, T = 0.003, 1.0, 0.5, 0.8


@pytest.fixture(scope="module")
def shaw_pierre_signals():
    """``x1'`` sampled at ``T = 0.8`` (4000 samples) from rest at
    ``x1 = x2 = 2/sqrt(3)`` and at ``(x1, x2) = (-2/3, 2/3)`` (the two
    trajectories of eq. 9.2), integrated by scipy's DOP853 at rtol 1e-12:
    both trajectories in one call."""

    def rhs(t, z):
        x1, x2, v1, v2 = z.reshape(4, -1)
        a1 = -C * v1 - K0 * x1 - KAPPA * x1**3 - K0 * (x1 - x2) - C * (v1 - v2)
        a2 = -C * v2 - K0 * x2 - K0 * (x2 - x1) - C * (v2 - v1)
        return np.concatenate([v1, v2, a1, a2])

    a = 2 / np.sqrt(3)
    t = T * np.arange(4000)
    z0 = np.array([a, -2 / 3, a, 2 / 3, 0, 0, 0, 0])
    sol = solve_ivp(
        rhs, (0, t[-1]), z0, method="DOP853", rtol=1e-12, atol=1e-14, t_eval=t
    )
    assert sol.success
    return [sol.y[4], sol.y[5]]


@pytest.mark.filterwarnings("ignore::ssm.errors.SsmWarning")
def test_shaw_pierre_identification_matches_the_closed_form(shaw_pierre_signals):
    """Reference (closed form, Sect. 9a): ``omega_1 = sqrt(k0) = 1``,
    ``omega_2 = sqrt(3 k0)``, ``zeta_1 = c / 2``, ``zeta_2 = sqrt(3) c / 2``.
    The map of order 9 on delay vectors of dimension 4 (relative weighting
    ``1/|xi|^2``, as the engine's test ``nar::shaw_pierre_linear_figures_
    from_noise_free_data``) identifies the frequencies to 1e-9 relative
    (measured 5e-12, 1e-10) and the damping ratios to 3e-6 (measured 4e-9,
    3.5e-7); the spectral quotients of eq. (5.10) are 3 and 0. The
    identified map's SSM gives the backbone of pair 1: its frequency at
    zero amplitude is the identified damped one, ``omega sqrt(1 - zeta^2)``,
    to 1e-9."""
    model = ssm.identify(
        shaw_pierre_signals,
        T,
        names=["x1_dot"],
        nu=2,
        order=9,
        weighting="relative",
        weight_power=2,
        floor=1e-5,
        rcond=1e-14,
    )
    d = model.diagnostics
    w_exact = np.array([1.0, np.sqrt(3.0)])
    z_exact = np.array([C / 2, np.sqrt(3.0) * C / 2])
    assert np.all(np.abs(d["frequencies"] / w_exact - 1) < 1e-9), d["frequencies"]
    assert np.all(np.abs(d["damping_ratios"] / z_exact - 1) < 3e-6), d["damping_ratios"]
    assert list(d["spectral_quotients"]) == [3.0, 0.0]
    assert model.outputs == ["x1_dot"]
    s = ssm.compute_ssm(model, [1], 5, progress=False)
    curve = s.backbone(rho_max=0.1, points=5, outputs=["x1_dot"])[0]
    damped = d["frequencies"][0] * np.sqrt(1 - d["damping_ratios"][0] ** 2)
    assert abs(curve.omega[0] / damped - 1) < 1e-9


@pytest.mark.parametrize(
    "signals, period, kwargs, words",
    [
        ([], 0.8, {}, "signals: no trajectory"),
        ([np.zeros((10, 2, 2))], 0.8, {}, "signals[0]: shape"),
        ([np.zeros(1)], 0.8, {}, "at least two samples"),
        ([np.arange(100)], 0.8, {}, "signals[0]: dtype int64"),
        ([np.full(100, np.nan)], 0.8, {}, "signals[0]: a non-finite sample at (0, 0)"),
        ([np.ones(100), np.ones((100, 2))], 0.8, {}, "signals[1]: 2 observable(s)"),
        ([np.ones(100)], 0.0, {}, "period: 0.0"),
        ([np.ones(100)], np.inf, {}, "period: inf"),
        ([np.ones(100)], 0.8, {"names": ["a", "b"]}, "names: 2 name(s)"),
        ([np.ones(100)], 0.8, {"reducer": "pod"}, "reducer: the NAR identifier has no"),
    ],
)
def test_bad_signals_are_refused_naming_the_argument(signals, period, kwargs, words):
    with pytest.raises(InputError) as e:
        ssm.identify(signals, period, **kwargs)
    assert words in str(e.value)


def test_the_identifier_names_its_own_failures(shaw_pierre_signals):
    """A misspelt parameter and signals too short for the delay embedding
    are the identifier's errors, with its message."""
    with pytest.raises(ModelError, match="ordr"):
        ssm.identify(shaw_pierre_signals, T, ordr=5)
    with pytest.raises(ModelError, match="samples"):
        ssm.identify([np.linspace(1, 0, 5)], T, nu=3)
