"""Bad input: each a typed exception (``ssm.errors.InputError``, a
``ValueError``) whose message names the argument and the problem."""

import numpy as np
import pytest
import ssm
from ssm.errors import InputError, ModelError, SsmError

F3 = (np.array([[0, 0, 0, 0]]), np.array([0.5]))


def model(**kw):
    args = {
        "M": np.eye(2),
        "K": np.diag([2.0, 7.0]),
        "C": 0.02 * np.eye(2),
        "f3": F3,
        "fext": np.ones(2),
    }
    args.update(kw)
    return ssm.from_arrays(**args)


@pytest.mark.parametrize(
    "kw, arg, words",
    [
        ({"M": np.ones((2, 3))}, "M", "square"),
        ({"M": np.zeros((0, 0))}, "M", "no degree of freedom"),
        ({"M": np.eye(2, dtype=int)}, "M", "dtype int"),
        ({"K": np.eye(2) * (1 + 1j)}, "K", "complex"),
        ({"K": np.array([[1.0, np.nan], [np.nan, 1.0]])}, "K", "finite"),
        ({"C": np.eye(3)}, "C", "shape (3, 3), expected (2, 2)"),
        ({"M": np.array([[1.0, 0.1], [0.0, 1.0]])}, "M", "not symmetric"),
        ({"f3": (np.array([[0, 0, 0, 5]]), np.array([1.0]))}, "f3", "outside 0..2"),
        ({"f3": (np.array([[0, 0, 0]]), np.array([1.0]))}, "f3", "expected (k, 4)"),
        ({"f3": (np.array([[0.0, 0, 0, 0]]), np.array([1.0]))}, "f3", "give integers"),
        ({"fext": np.ones(3)}, "fext", "expected (2,)"),
        ({"outputs": {"y": 7}}, "outputs", "outside 0..2"),
        ({"C": np.eye(2), "rayleigh": (0.1, 0.0)}, "rayleigh", "not both"),
    ],
)
def test_bad_arrays_are_refused_naming_the_argument(kw, arg, words):
    with pytest.raises(InputError) as e:
        model(**kw)
    msg = str(e.value)
    assert msg.startswith(f"{arg}:") and words in msg, msg
    assert isinstance(e.value, ValueError) and isinstance(e.value, SsmError)


def test_a_massless_degree_of_freedom_is_a_model_error():
    with pytest.raises(ModelError, match="M: "):
        model(M=np.diag([1.0, 0.0]))


def test_bad_requests_are_refused_naming_the_argument():
    s = ssm.compute_ssm(model(), [1], 5)
    with pytest.raises(InputError, match="no output 'nope'"):
        s.backbone(0.1, outputs=["nope"])
    with pytest.raises(InputError, match="rho_max"):
        s.backbone(float("nan"))
    with pytest.raises(InputError, match="normalization"):
        ssm.compute_ssm(model(), [1], 5, normalization="bogus")
    with pytest.raises(SsmError, match="master"):
        ssm.compute_ssm(model(), [7], 5)
    unforced = ssm.compute_ssm(model(fext=None), [1], 5)
    with pytest.raises(InputError, match="fext"):
        unforced.forced_response([0.01], (0.9, 1.1))


def test_a_missing_folder_is_an_input_error(tmp_path):
    with pytest.raises(InputError):
        ssm.from_files(tmp_path / "nowhere")


def test_oversized_requests_are_refused_by_the_cost_gate():
    """The engine's one gate, as for a scene: an order of 1e9 and 1e12
    points are refused before anything is allocated, naming the key that
    sets the size (they hung or ran out of memory before the gate)."""
    with pytest.raises(InputError, match="ssm.order"):
        ssm.compute_ssm(model(), [1], 10**9)
    s = ssm.compute_ssm(model(), [1], 5)
    with pytest.raises(InputError, match="backbone.points"):
        s.backbone(0.1, points=10**12)
    with pytest.raises(InputError, match="forcing.points"):
        s.forced_response([0.01], (0.9, 1.1), points=10**12)


def test_a_model_over_the_memory_limit_is_refused_before_it_is_built():
    """Under ``ulimit -v`` of 3 GB (a child process), a model of 3 x 10^6
    degrees of freedom from scipy (6 x 10^6 stored entries, about 3.6 GB to
    build at the measured 430-460 bytes an entry) is an InputError naming
    ``M`` and the address-space limit, not an abort of the process; the same
    call with 10^4 degrees of freedom builds."""
    import subprocess
    import sys
    import textwrap

    script = textwrap.dedent(
        """
        import resource, sys
        import scipy.sparse as sp, ssm
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
        n = int(sys.argv[1])
        try:
            ssm.from_arrays(sp.identity(n, format="csr"), sp.identity(n, format="csr"))
            print("built")
        except ssm.errors.InputError as e:
            print("refused:", e)
        """
    )
    out = {
        n: subprocess.run(
            [sys.executable, "-c", script, str(n)],
            check=False,
            capture_output=True,
            text=True,
            timeout=120,
        )
        for n in (3_000_000, 10_000)
    }
    big, small = out[3_000_000], out[10_000]
    assert big.returncode == 0, big.stderr
    assert big.stdout.startswith("refused: M:") and "ulimit -v" in big.stdout, (
        big.stdout
    )
    assert small.stdout.strip() == "built", small.stdout + small.stderr
