"""The POD study of a model from arrays: a training run, its proper
orthogonal decomposition and the Galerkin models (Stadlmayr, Witteveen &
Steiner 2017), against the modal closed form."""

import numpy as np
import pytest
import scipy.linalg
import ssm


def chain(n=20):
    """``n`` unit masses in a Dirichlet chain, Rayleigh damping, and its
    modes (mass-normalized)."""
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    M = np.eye(n)
    _, phi = scipy.linalg.eigh(K, M)
    return M, K, phi


@pytest.mark.parametrize("modes", [(0, 1), (0, 2, 5)])
def test_the_pod_of_a_load_on_some_modes_keeps_exactly_those(modes):
    """Reference (modal closed form): a linear model forced from rest by a
    load shape ``M (phi_a + phi_b + ...)`` moves in the span of those modes
    only, so the POD of its training run has exactly as many POVs above
    round-off (the next below 1e-10 of the first; measured 2.8e-15 and
    1.2e-12), the
    truncation at a drop of 6 decades keeps them, and the reduced model
    reproduces the full run to 1e-10 (measured 2.4e-14 at most) on the training load
    and on a load of another amplitude and frequency. A start outside that
    span (a displacement of one mass) is not represented: the error there
    is above 10 % (measured 94 % and 79 %), as the method predicts."""
    M, K, phi = chain()
    fext = M @ phi[:, list(modes)].sum(axis=1)
    model = ssm.from_arrays(
        M, K, rayleigh=(0.0, 0.01), fext=fext, outputs={"mid": 10, "end": 19}
    )
    study = ssm.pod(
        model,
        train={"t_end": 200.0, "epsilon": 0.01, "omega": 0.2},
        step=0.05,
        tests=[
            {"t_end": 200.0, "epsilon": 0.02, "omega": 0.1},
            {"t_end": 50.0, "start": [["x5", 0.1]]},
        ],
        outputs=["mid", "end"],
    )
    summary = study.summary["pod"]
    (pod1,) = summary["pod_models"]
    assert pod1["reduced_coordinates"] == len(modes)
    povs = study.table("pod_povs.csv")["relative"].to_numpy()
    assert np.all(povs[: len(modes)] > 1e-6) and povs[len(modes)] < 1e-10
    train, unseen, outside = (c["runs"][0]["max_error"] for c in summary["cases"])
    assert train < 1e-10 and unseen < 1e-10, (train, unseen)
    assert outside > 0.1, outside
    assert "pod_comparison.csv" in study.files


def test_a_model_identified_from_data_has_no_pod_study():
    t = np.arange(400) * 0.1
    model = ssm.identify(np.exp(-0.01 * t) * np.cos(t), 0.1, nu=1, order=1)
    with pytest.raises(ssm.errors.InputError, match="pod"):
        ssm.pod(model, train={"t_end": 1.0}, step=0.1)
