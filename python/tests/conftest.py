"""Models shared by the tests."""

import numpy as np
import pytest
import ssm


def duffing(zeta=0.01, w=1.0, kappa=0.5):
    """``x'' + 2 zeta w x' + w^2 x + kappa x^3 = eps cos(Omega t)``."""
    return ssm.from_arrays(
        M=np.eye(1),
        K=np.array([[w * w]]),
        C=np.array([[2.0 * zeta * w]]),
        f3=(np.array([[0, 0, 0, 0]]), np.array([kappa])),
        fext=np.ones(1),
        outputs={"x": 0},
        name="duffing",
    )


@pytest.fixture
def duffing_model():
    return duffing()
