"""Scene files as a door: the model of a scene and its whole run, from
Python, as the command line gives them."""

import json
import os
import subprocess

import numpy as np
import pytest
import ssm
from ssm.errors import InputError, ModelError
from test_plugins import RELEASE, ROOT, library

SCENE = ROOT / "zoo" / "spatial_oscillator_cubic.toml"


def plugins():
    return [library("spatial-oscillator")]


def test_the_model_of_a_scene_has_the_papers_eigenvalues():
    """Reference: Li, Jain & Haller (2023), eqs. (26)-(27), printed digits:
    ``-0.02 +- 1.9999i`` and ``-0.15 +- 2.9962i`` for the cubic constraint
    (two pairs; the constraint's infinite modes are not among them)."""
    model = ssm.from_scene(SCENE, plugins())
    assert model.n_states == 7
    lam = model.spectrum()
    upper = lam[lam.imag > 0]
    upper = upper[np.argsort(upper.imag)]
    for got, (re, im) in zip(upper, [(-0.02, 1.9999), (-0.15, 2.9962)]):
        assert abs(got.real - re) <= 0.005 and abs(got.imag - im) <= 0.00005, got
    assert len(upper) == 2


def test_a_scene_run_writes_what_the_command_line_writes(tmp_path):
    """Determinism check across the two doors: the bundled scene run from
    Python writes the files the ``ssm-engine`` binary writes, and the same
    figures in ``summary.json`` (every number but the timings)."""
    run = ssm.run_scene(SCENE, plugins(), progress=False)
    engine = RELEASE / "ssm-engine"
    subprocess.run(
        [str(engine), str(SCENE), "--out", str(tmp_path)],
        check=True,
        capture_output=True,
        env={**os.environ, "SSM_PLUGIN_PATH": str(RELEASE)},
    )
    # (the binary also leaves its marker of an output folder, a hidden file)
    written = sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith("."))
    assert sorted(run.files) == written
    cli = json.loads((tmp_path / "summary.json").read_text())

    def figures(value):
        """The summary without its clocks (keys in seconds or per second),
        its memory and the plugins' paths."""
        if isinstance(value, dict):
            return {
                k: figures(v)
                for k, v in value.items()
                if not (k.endswith("_s") or k in ("timing_s", "memory", "plugins"))
            }
        if isinstance(value, list):
            return [figures(v) for v in value]
        return value

    assert figures(run.summary) == figures(cli)
    assert run.summary["spectrum"] == cli["spectrum"]
    for name in ("backbone.csv", "spectrum.csv", "invariance.csv"):
        assert run.files[name] == (tmp_path / name).read_bytes(), name
    # the README's picture is the bundled scene's backbone.svg as the engine
    # draws it now
    picture = ROOT / "docs" / "images" / "backbone.svg"
    assert run.files["backbone.svg"] == picture.read_bytes(), (
        "docs/images/backbone.svg is not what the bundled scene draws: copy "
        "out/spatial_oscillator_cubic/backbone.svg there"
    )


def test_bad_scenes_are_named(tmp_path):
    """A missing file, a FIFO, a TOML error (its file and line) and an unknown plugin
    are exceptions naming the problem; nothing hangs."""
    with pytest.raises(InputError, match="nowhere.toml"):
        ssm.from_scene(tmp_path / "nowhere.toml")
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)
    with pytest.raises(InputError):
        ssm.from_scene(fifo)
    bad = tmp_path / "bad.toml"
    bad.write_text("[model]\nplugin = \n")
    with pytest.raises(InputError, match="bad.toml:2:"):
        ssm.from_scene(bad)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text('[model]\nplugin = "no-such-plugin"\n')
    with pytest.raises((InputError, ModelError), match="no-such-plugin"):
        ssm.from_scene(unknown)
