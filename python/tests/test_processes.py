"""The package in processes and threads: forked children, threads that run experiments side by
side, signals while rendering or saving (issue 54 #2, #4, #10, #18)."""

import textwrap

from conftest import run_python


def test_a_forked_child_renders_after_the_parent_loaded_and_rendered():
    # Before: rayon's global pool survived the fork without its threads, and the child's
    # first render waited forever.
    code = textwrap.dedent(
        """
        import os, sys, time
        import numpy as np
        import refract

        scene = refract.Scene.load("sphere")
        before = scene.render("wyman", res=(32, 32)).color
        pid = os.fork()
        if pid == 0:
            after = scene.render("wyman", res=(32, 32)).color
            os._exit(0 if np.array_equal(before, after) else 3)
        deadline = time.time() + 120
        while time.time() < deadline:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                sys.exit(os.waitstatus_to_exitcode(status))
            time.sleep(0.05)
        os.kill(pid, 9)
        sys.exit("the forked child's render did not return in 120 s")
        """
    )
    result = run_python(code, timeout=200)
    assert result.returncode == 0, result.stderr


def test_multiprocessing_pools_render_with_the_fork_start_method():
    code = textwrap.dedent(
        """
        import multiprocessing as mp
        import refract

        scene = refract.Scene.load("sphere")
        scene.render("single", res=(16, 16))

        def mean(method):
            return float(scene.render(method, res=(24, 24)).color.mean())

        if __name__ == "__main__":
            with mp.get_context("fork").Pool(2) as pool:
                values = pool.map_async(mean, ["single", "wyman", "wyman-dn"]).get(120)
            assert len(values) == 3 and all(v > 0 for v in values), values
        """
    )
    result = run_python(code, timeout=200)
    assert result.returncode == 0, result.stderr


def test_an_experiment_failing_in_one_thread_leaves_another_threads_output(tmp_path):
    # Before: the failing compare removed every directory any experiment of the process had
    # created, the other thread's output included, and every file being written.
    import threading

    import refract

    good, bad = tmp_path / "good", tmp_path / "bad"
    outcome = {}

    def long_compare():
        try:
            outcome["records"] = refract.compare(
                "sphere", methods=["single", "wyman", "wyman-dn"], res=64, frames=2, out=good
            )
        except Exception as err:  # the assertion below reports it
            outcome["error"] = err

    worker = threading.Thread(target=long_compare)
    worker.start()
    while not good.exists() and worker.is_alive():
        pass
    try:
        refract.compare("no-such-scene", methods=["single"], res=16, out=bad)
    except ValueError as err:
        assert "no-such-scene" in str(err)
    else:
        raise AssertionError("an unknown scene must fail")
    assert not bad.exists(), "the failing experiment leaves its own directory behind"
    worker.join()
    assert "error" not in outcome, outcome.get("error")
    assert (good / "metrics.json").is_file()
    assert len(outcome["records"]) == 4


def test_ctrl_c_interrupts_a_long_render():
    # Before: KeyboardInterrupt came only when the frame was done (hours for this one: a
    # 1024² reference at 4096 samples per pixel). The subprocess timeout is the failure.
    code = textwrap.dedent(
        """
        import os, signal, threading
        import refract

        scene = refract.Scene.load("sphere")
        threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        try:
            scene.render("reference", res=(1024, 1024), params={"spp": 4096})
        except KeyboardInterrupt:
            print("interrupted")
        """
    )
    result = run_python(code, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "interrupted"


def test_sigterm_while_saving_leaves_no_temporary(tmp_path):
    # Before: `.frame.exr.XXXXXX.partial` stayed beside the frame. Now the file being written
    # has no name until it is finished (docs/python.md).
    import signal
    import subprocess
    import sys
    import time

    code = textwrap.dedent(
        f"""
        import refract
        frame = refract.Scene.load("sphere").render("reference", res=(512, 512), aovs=True)
        print("saving", flush=True)
        while True:
            frame.save({str(tmp_path / "frame.exr")!r})
        """
    )
    env = dict(__import__("os").environ)
    env["PYTHONPATH"] = __import__("os").pathsep.join(p for p in sys.path if p)
    child = subprocess.Popen(
        [sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout.readline().strip() == "saving"
        time.sleep(0.5)
        child.send_signal(signal.SIGTERM)
        assert child.wait(timeout=60) == -signal.SIGTERM
    finally:
        child.kill()
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left in ([], ["frame.exr"]), left
