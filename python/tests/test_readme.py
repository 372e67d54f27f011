"""The README's Python example runs as printed (a newcomer copies it)."""

import pathlib
import re
import runpy

import matplotlib

matplotlib.use("Agg")

README = pathlib.Path(__file__).resolve().parents[2] / "README.md"


def test_the_readme_python_example_runs(tmp_path):
    """The block is executed as it stands; its answers are the objects the
    docs describe (reference: the Duffing oscillator of ``zeta = 0.01``
    past its folds has two saddle-node bifurcations on the full system's
    branch)."""
    text = README.read_text()
    (block,) = re.findall(r"```python\n(import .*?)```", text, re.DOTALL)
    script = tmp_path / "readme_example.py"
    script.write_text(block)
    names = runpy.run_path(str(script))
    assert names["backbone"].order == 7
    assert len(names["frc"].to_pandas()) > 50
    assert [e["kind"] for e in names["ref"].events] == ["SN", "SN"]
