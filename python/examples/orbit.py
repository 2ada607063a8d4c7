"""Orbit the camera around a scene and plot each method's error against the view angle.

    python python/examples/orbit.py [--scene torus] [--steps 24] [--res 192] [--out orbit.png]
"""

import argparse
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import refract  # noqa: E402

METHODS = ["single", "wyman", "proxy-sphere"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="torus")
    parser.add_argument("--steps", type=int, default=24)
    parser.add_argument("--res", type=int, default=192)
    parser.add_argument("--out", default="orbit.png")
    args = parser.parse_args()

    scene = refract.Scene.load(args.scene)
    ex, ey, ez = scene.eye
    tx, ty, tz = scene.target
    radius = math.hypot(ex - tx, ez - tz)
    angles = [360.0 * k / args.steps for k in range(args.steps)]
    errors = {m: [] for m in METHODS}
    res = (args.res, args.res)
    for angle in angles:
        a = math.radians(angle)
        # Around the vertical axis through the target, at the scene's own height.
        scene.eye = (tx + radius * math.sin(a), ey, tz + radius * math.cos(a))
        reference = scene.render("reference", res=res, aovs=True)
        for method in METHODS:
            frame = scene.render(method, res=res, aovs=True)
            errors[method].append(refract.metrics(frame, reference)["flip_mean"])
        print(f"{angle:6.1f} deg  " + "  ".join(f"{m} {errors[m][-1]:.3f}" for m in METHODS))

    fig, ax = plt.subplots(figsize=(7, 4))
    for method in METHODS:
        ax.plot(angles, errors[method], marker="o", markersize=3, label=method)
    ax.set_xlabel("camera angle around the vertical axis (degrees)")
    ax.set_ylabel("mean FLIP over refractor pixels")
    ax.set_xlim(0, 360)
    ax.set_ylim(bottom=0)
    ax.grid(True, color="0.9")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax.set_title(f"{scene.name}: error against the view angle ({res[0]}x{res[1]})")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
