"""The exact reference's closest-hit throughput against Embree's, per core, on the same
triangles and the same rays in one process (docs/performance.md, "The tracer against Embree").

    python python/benchmarks/embree.py [--data ../shared/data] [--meshes stanford-bunny,horse]
                                       [--rays 1048576] [--rounds 5]

Needs `refract` (the extension module, e.g. `pip install ./python`), numpy and `embreex`
(Embree 4 through Cython: `pip install embreex`). Both tracers run on one thread: refract's
`Tracer.closest_hits` traces its rays in a loop on the calling thread, and embreex's
`EmbreeScene.run` calls `rtcIntersect1` ray by ray. Each mesh is loaded once by refract (centred
and scaled into the unit sphere) and handed to Embree as the same float32 vertices and triangles.

Two ray sets per mesh, each of `--rays` rays:
  camera      a pinhole camera 3 units from the centre on +z, its square image just covering
              the unit sphere, one ray per pixel (coherent: neighbours traverse the same nodes);
  incoherent  origins uniform on the sphere of radius 2, each towards a point uniform in the
              unit ball (seeded): neighbouring rays share nothing.
The two tracers alternate in `--rounds` rounds; each rate is the median over rounds (rays per
second, hits and misses alike). Their answers are compared: the share of rays where both miss,
or both hit the same triangle, or hit at distances within 1e-4 (a shared edge).
"""

import argparse
import math
import os
import statistics
import sys
import time

import numpy as np

import refract


def camera_rays(n):
    """`n` (rounded down to a square) rays of a pinhole at (0, 0, 3) looking at the origin,
    its image plane just covering the unit sphere."""
    side = int(math.isqrt(n))
    half = math.tan(math.asin(1.0 / 3.0))
    coords = (np.arange(side, dtype=np.float64) + 0.5) / side * 2.0 - 1.0
    x, y = np.meshgrid(coords * half, -coords * half)
    directions = np.stack([x.ravel(), y.ravel(), -np.ones(side * side)], axis=1)
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    origins = np.tile(np.array([0.0, 0.0, 3.0]), (side * side, 1))
    return origins.astype(np.float32), directions.astype(np.float32)


def incoherent_rays(n, seed=1):
    """`n` rays from uniform points on the sphere of radius 2 towards uniform points in the
    unit ball."""
    rng = np.random.default_rng(seed)
    on_sphere = rng.normal(size=(n, 3))
    on_sphere /= np.linalg.norm(on_sphere, axis=1, keepdims=True)
    origins = 2.0 * on_sphere
    in_ball = rng.normal(size=(n, 3))
    in_ball /= np.linalg.norm(in_ball, axis=1, keepdims=True)
    in_ball *= rng.random(size=(n, 1)) ** (1.0 / 3.0)
    directions = in_ball - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return origins.astype(np.float32), directions.astype(np.float32)


def embree_scene(tracer):
    """An Embree scene of the tracer's triangles (the same float32 vertices)."""
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, tracer.vertices, tracer.triangles.astype(np.int32))
    return scene


def embree_hits(scene, origins, directions):
    """Embree's closest hits as refract returns them: (t, triangle), inf and -1 for a miss."""
    result = scene.run(origins, directions, output=1)
    triangle = result["primID"].astype(np.int64)
    t = np.where(triangle >= 0, result["tfar"], np.inf).astype(np.float32)
    return t, triangle


def agreement(a, b):
    """The share of rays on which two (t, triangle) answers agree."""
    (ta, pa), (tb, pb) = a, b
    both_miss = (pa < 0) & (pb < 0)
    with np.errstate(invalid="ignore"):  # inf - inf where both miss: not counted below
        near = np.abs(ta - tb) <= 1e-4 * np.maximum(1.0, ta)
    same = (pa >= 0) & (pb >= 0) & ((pa == pb) | near)
    return float(np.mean(both_miss | same))


def measure(tracer, scene, origins, directions, rounds):
    """Median rays per second of each tracer over alternating rounds, and their agreement."""
    ours, theirs = [], []
    answers = None
    for _ in range(rounds):
        start = time.perf_counter()
        a = tracer.closest_hits(origins, directions)
        ours.append(len(origins) / (time.perf_counter() - start))
        start = time.perf_counter()
        b = embree_hits(scene, origins, directions)
        theirs.append(len(origins) / (time.perf_counter() - start))
        answers = (a, b)
    hit_share = float(np.mean(answers[0][1] >= 0))
    return statistics.median(ours), statistics.median(theirs), agreement(*answers), hit_share


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=os.path.join("..", "shared", "data"))
    parser.add_argument("--meshes", default="stanford-bunny,horse")
    parser.add_argument("--rays", type=int, default=1 << 20)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    if not 1 <= args.rays <= 1 << 24:
        parser.error(f"--rays: expected 1 to {1 << 24}, got {args.rays}")
    if not 1 <= args.rounds <= 50:
        parser.error(f"--rounds: expected 1 to 50, got {args.rounds}")
    try:
        import embreex
    except ImportError:
        sys.exit("embree.py: needs embreex (pip install embreex)")

    embreex_version = getattr(embreex, "__version__", "?")
    print(
        f"| mesh | triangles | rays | refract (Mrays/s, 1 thread) | Embree (embreex "
        f"{embreex_version}; Mrays/s, 1 thread) | refract / Embree | rays that hit | answers agree |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name in args.meshes.split(","):
        path = os.path.join(args.data, "meshes", f"{name}.obj")
        if not os.path.isfile(path):
            sys.exit(f"embree.py: {path} not found (--data)")
        tracer = refract.Tracer.load(path)
        scene = embree_scene(tracer)
        for kind, rays in [("camera", camera_rays), ("incoherent", incoherent_rays)]:
            origins, directions = rays(args.rays)
            ours, theirs, agree, hits = measure(tracer, scene, origins, directions, args.rounds)
            print(
                f"| {name} | {len(tracer.triangles):,} | {kind} ({len(origins):,}) | "
                f"{ours / 1e6:.2f} | {theirs / 1e6:.2f} | {ours / theirs:.2f} | "
                f"{100 * hits:.1f} % | {100 * agree:.3f} % |"
            )


if __name__ == "__main__":
    main()
