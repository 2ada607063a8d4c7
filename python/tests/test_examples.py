"""The examples run and write their figures (at a small size)."""

import subprocess
import sys
from pathlib import Path

import pytest
from conftest import optional_module

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.mark.parametrize(
    "script, args",
    [
        ("compare_methods.py", ["--res", "48"]),
        ("orbit.py", ["--res", "32", "--steps", "3"]),
    ],
)
def test_example_writes_its_figure(script, args, tmp_path):
    optional_module("matplotlib")
    out = tmp_path / "figure.png"
    result = subprocess.run(
        [sys.executable, str(EXAMPLES / script), *args, "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 10_000
