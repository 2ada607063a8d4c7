"""What a render from Python costs over the same render in Rust.

For each frame, the wall time of `scene.render(...)` in Python (argument parsing, the GIL
released and taken back, the frame checks and allocation of `refract_lab::render`, the copy into
the numpy array) against the frame's own time as the renderer measured it (`frame.timing`,
every per-frame pass: what `refract compare` and `refract bench` report). Medians over
alternating runs after warm-up frames.

    python python/benchmarks/overhead.py [--method wyman] [--res 512] [--frames 40]
"""

import argparse
import statistics
import time

import refract


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="sphere")
    parser.add_argument("--method", default="wyman")
    parser.add_argument("--backend", default="cpu")
    parser.add_argument("--res", type=int, default=512)
    parser.add_argument("--frames", type=int, default=40)
    args = parser.parse_args()

    scene = refract.Scene.load(args.scene)
    res = (args.res, args.res)
    for _ in range(3):
        scene.render(args.method, backend=args.backend, res=res).color
    wall, inner = [], []
    for _ in range(args.frames):
        start = time.perf_counter()
        frame = scene.render(args.method, backend=args.backend, res=res)
        frame.color  # the copy into numpy is part of the cost
        wall.append((time.perf_counter() - start) * 1e3)
        inner.append(frame.timing["ms"])
    w, r = statistics.median(wall), statistics.median(inner)
    print(
        f"{args.scene} {args.method} {args.backend} {res[0]}x{res[1]}: "
        f"Python call {w:.2f} ms, renderer {r:.2f} ms, overhead {w - r:.2f} ms ({100 * (w / r - 1):.1f} %)"
    )


if __name__ == "__main__":
    main()
