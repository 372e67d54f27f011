"""Models from plugin libraries: the same model as from arrays, and a
plugin's failure or panic as a Python exception."""

import os
import pathlib

import numpy as np
import pytest
import ssm
from conftest import duffing
from ssm.errors import ModelError

ROOT = pathlib.Path(__file__).resolve().parents[2]
RELEASE = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "release"


def library(crate):
    """The plugin library of the workspace crate ``crate`` (built by
    ``cargo build --release --workspace``)."""
    path = RELEASE / f"lib{crate.replace('-', '_')}.so"
    assert path.exists(), f"{path}: build the workspace first"
    return str(path)


def test_the_plugin_and_the_arrays_give_the_same_spectrum_and_ssm():
    """Reference: the `duffing` plugin's model with the same parameters.
    Spectra and the coefficients of W at O(9) agree to 1e-12 relative."""
    zeta, w, kappa = 0.02, 1.3, 0.7
    plugin = ssm.from_plugin(library("duffing"), zeta=zeta, omega=w, kappa=kappa)
    arrays = duffing(zeta, w, kappa)
    assert np.allclose(plugin.spectrum(), arrays.spectrum(), rtol=1e-12, atol=0)
    a = ssm.compute_ssm(plugin, [1], 9).w
    b = ssm.compute_ssm(arrays, [1], 9).w
    assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max()


def test_a_panic_inside_a_plugin_is_a_model_error():
    with pytest.raises(ModelError, match="fixture panic: index 3 out of range"):
        ssm.from_plugin(library("ssm-fixture-panicking"), "panics")
    # the process goes on, and the plugin answers again
    with pytest.raises(ModelError, match="not symmetric"):
        ssm.from_plugin(library("ssm-fixture-panicking"), "fails")


def test_plugin_failures_name_what_is_wrong():
    with pytest.raises(ModelError, match="kapa"):
        ssm.from_plugin(library("duffing"), kapa=1.0)
    with pytest.raises(ModelError, match="no plugin named 'no-such-plugin'"):
        ssm.from_plugin("no-such-plugin")
    with pytest.raises(ssm.errors.InputError, match="params: zeta"):
        ssm.from_plugin(library("duffing"), zeta=object())
