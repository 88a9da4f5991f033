"""The README's Python example runs as printed (on the example logs of this build)."""

import os
import pathlib
import warnings

import pytest

README = pathlib.Path(__file__).resolve().parents[2] / "README.md"


def test_the_readme_example_runs(data_dir, tmp_path):
    pytest.importorskip("control")
    text = README.read_text()
    start = text.index("```python\nimport control, sysid")
    code = text[start + len("```python\n"):text.index("```", start + 10)]
    code = code.replace("build/release/data", str(data_dir))
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            exec(compile(code, str(README), "exec"), {})
    finally:
        os.chdir(cwd)
    assert (tmp_path / "par2_moesp.json").exists()
