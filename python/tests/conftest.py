"""Shared fixtures. The package under test is the one on PYTHONPATH: tests/pytest.rs puts the
extension module `cargo test` built there; after `pip install ./python` it is the installed one."""

import os
import subprocess
import sys

import pytest

import refract


@pytest.fixture(scope="session")
def sphere():
    return refract.Scene.load("sphere")


@pytest.fixture(scope="session")
def gpu_available():
    """Whether a GPU adapter opens (lavapipe counts); REFRACT_REQUIRE_GPU=1 makes its absence
    a failure instead of a skip."""
    try:
        refract.Scene.load("sphere").render("single", backend="gpu", res=(8, 8))
        return True
    except refract.RenderError as err:
        if os.environ.get("REFRACT_REQUIRE_GPU") == "1":
            pytest.fail(f"REFRACT_REQUIRE_GPU=1 but the GPU backend cannot run: {err}")
        return False


def run_python(code, env=None, timeout=300):
    """Runs `code` in a fresh interpreter with this one's path (for what must not touch the
    test process: environment variables read at start, signals)."""
    full_env = dict(os.environ)
    full_env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
    full_env.update(env or {})
    return subprocess.run(
        [sys.executable, "-c", code],
        env=full_env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def optional_module(name):
    """`name` imported, or the test skipped without it (failed under REFRACT_REQUIRE_PYTHON=1,
    where .ci/run has installed it)."""
    try:
        return __import__(name)
    except ImportError:
        if os.environ.get("REFRACT_REQUIRE_PYTHON") == "1":
            pytest.fail(f"REFRACT_REQUIRE_PYTHON=1 but {name} is not installed")
        pytest.skip(f"{name} is not installed")
