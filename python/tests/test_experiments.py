"""refract.compare and refract.sweep: the CLI's experiments, records for pandas."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

import refract
from conftest import optional_module

SWEEP = """
scenes = ["sphere", "torus"]
methods = ["single", "wyman"]
res = [32]
frames = 1
params = { tir = ["clamp", "black"] }
"""


def test_compare_returns_records_and_writes_the_report(tmp_path):
    records = refract.compare(
        ["sphere", "torus"], methods=["single", "wyman"], res=32, frames=1, out=tmp_path / "out"
    )
    assert [(r["scene"], r["method"]) for r in records] == [
        ("sphere", "reference"),
        ("sphere", "single"),
        ("sphere", "wyman"),
        ("torus", "reference"),
        ("torus", "single"),
        ("torus", "wyman"),
    ]
    assert all(r["ms_per_frame"] > 0 for r in records if r["method"] != "reference")
    for name in ("metrics.json", "report.md", "index.html", "sphere/wyman-cpu.png"):
        assert (tmp_path / "out" / name).exists(), name
    pandas = optional_module("pandas")
    table = pandas.DataFrame(records)
    assert len(table) == 6 and "flip_mean" in table.columns


def test_compare_against_the_gpu_reference(tmp_path, gpu_available):
    if not gpu_available:
        pytest.skip("no GPU adapter")
    cpu = refract.compare("sphere", methods=["wyman"], res=32, frames=1, out=tmp_path / "c")
    gpu = refract.compare(
        "sphere", methods=["wyman"], res=32, frames=1, out=tmp_path / "g", reference_backend="gpu"
    )
    assert [r["backend"] for r in cpu] == ["trace", "cpu"]
    assert [r["backend"] for r in gpu] == ["gpu", "cpu"]
    # The same FLIP against either reference, within the two references' f32 differences.
    assert abs(cpu[1]["flip_mean"] - gpu[1]["flip_mean"]) <= 1e-3 * (1 + cpu[1]["flip_mean"])


def test_compare_bad_inputs(tmp_path):
    with pytest.raises(ValueError, match="unknown method"):
        refract.compare("sphere", methods=["nope"], out=tmp_path / "a")
    with pytest.raises(ValueError, match="reference is always rendered"):
        refract.compare("sphere", methods=["reference"], out=tmp_path / "a")
    with pytest.raises(ValueError, match="res = 0"):
        refract.compare("sphere", res=0, out=tmp_path / "a")
    with pytest.raises(ValueError, match="none of the selected methods"):
        refract.compare("sphere", methods=["single"], params={"seeds": 3}, out=tmp_path / "a")
    with pytest.raises(TypeError, match="params"):
        refract.compare("sphere", methods=["wyman"], params={"tir": True}, out=tmp_path / "a")
    with pytest.raises(ValueError, match="reference_backend"):
        refract.compare("sphere", methods=["single"], reference_backend="tpu", out=tmp_path / "a")
    with pytest.raises(ValueError, match="unknown scene"):
        refract.compare("nowhere", methods=["single"], res=8, out=tmp_path / "b")
    # A failed comparison leaves no half-made output directory.
    assert not (tmp_path / "b").exists()


def test_sweep_runs_shards_and_resumes(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SWEEP)
    out = tmp_path / "out"
    first = refract.sweep(path, shard=(0, 2), out=out)
    second = refract.sweep(path, shard=(1, 2), out=out)
    # 2 scenes x (single, wyman with 2 tir values): single has no `tir`.
    assert len(first) + len(second) == 6
    assert {r["id"] for r in first}.isdisjoint({r["id"] for r in second})
    assert all(r["status"] == "ok" for r in first + second), first + second
    assert {r.get("param.tir") for r in first + second} == {None, "clamp", "black"}
    assert all(0 < r["flip_mean"] < 1 for r in first)
    # Finished jobs are not run again: the same records come back.
    again = refract.sweep(path, shard=(0, 2), out=out)
    assert again == first
    pandas = optional_module("pandas")
    assert len(pandas.DataFrame(first + second)) == 6


def test_sweep_bad_inputs(tmp_path):
    with pytest.raises(FileNotFoundError):
        refract.sweep(tmp_path / "missing.toml", out=tmp_path / "o")
    path = tmp_path / "s.toml"
    path.write_text(SWEEP)
    with pytest.raises(ValueError, match="shard"):
        refract.sweep(path, shard=(2, 2), out=tmp_path / "o")
    path.write_text(SWEEP.replace("single", "no-such-method"))
    with pytest.raises(ValueError, match="no-such-method"):
        refract.sweep(path, out=tmp_path / "o")


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process")
def test_ctrl_c_stops_a_sweep_between_jobs(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SWEEP.replace("res = [32]", "res = [256]").replace("frames = 1", "frames = 30"))
    out = tmp_path / "out"
    code = textwrap.dedent(
        f"""
        import refract
        try:
            refract.sweep({str(path)!r}, out={str(out)!r})
        except KeyboardInterrupt:
            print("interrupted")
        """
    )
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    child = subprocess.Popen(
        [sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, text=True
    )
    jobs = out / "jobs"
    deadline = time.monotonic() + 240
    while not (jobs.exists() and any(jobs.iterdir())):
        assert time.monotonic() < deadline, "the sweep never finished a job"
        assert child.poll() is None, "the sweep ended before it was interrupted"
        time.sleep(0.02)
    child.send_signal(signal.SIGINT)
    stdout, _ = child.communicate(timeout=240)
    assert "interrupted" in stdout
    finished = len(list(jobs.iterdir()))
    assert 1 <= finished < 6, finished


def test_compare_with_an_engine_itself(tmp_path):
    """three.js itself as a row beside the methods (docs/engines.md); without Node, Chromium or
    the npm packages the test is skipped, failed under REFRACT_REQUIRE_ENGINES=1."""
    try:
        records = refract.compare(
            "chart",
            methods=["volume-thickness"],
            res=32,
            frames=1,
            out=tmp_path / "e",
            engines=["threejs"],
        )
    except Exception as err:  # the driver's one line naming what is missing
        if os.environ.get("REFRACT_REQUIRE_ENGINES") == "1":
            raise
        pytest.skip(str(err))
    engine = [r for r in records if r["method"].startswith("threejs@")]
    assert len(engine) == 1 and engine[0]["backend"] == "webgl"
    assert 0 < engine[0]["flip_mean"] < 1
    with pytest.raises(ValueError, match="unknown engine `unity`"):
        refract.compare("sphere", engines=["unity"], out=tmp_path / "u")
