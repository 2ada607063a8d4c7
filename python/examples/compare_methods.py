"""Three methods and the exact reference on one scene: images, FLIP maps and a metrics table
in one matplotlib figure.

    python python/examples/compare_methods.py [--scene torus] [--res 384] [--out compare.png]
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import refract  # noqa: E402

METHODS = ["single", "wyman", "volume-thickness"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="torus")
    parser.add_argument("--res", type=int, default=384)
    parser.add_argument("--out", default="compare.png")
    args = parser.parse_args()

    scene = refract.Scene.load(args.scene)
    res = (args.res, args.res)
    reference = scene.render("reference", res=res, aovs=True)
    rows = []
    columns = len(METHODS) + 1
    fig = plt.figure(figsize=(3.3 * columns + 1.0, 8.6), layout="constrained")
    grid = fig.add_gridspec(3, columns, height_ratios=[1, 1, 0.42])
    axes = np.array([[fig.add_subplot(grid[r, c]) for c in range(columns)] for r in range(2)])
    axes[0, 0].imshow(reference.srgb8())
    axes[0, 0].set_title(f"reference ({reference.timing['ms']:.0f} ms)")
    covered = reference.aov("covered")
    axes[1, 0].imshow(covered, cmap="gray")
    axes[1, 0].set_title("refractor pixels (metrics)")
    for column, method in enumerate(METHODS, start=1):
        frame = scene.render(method, res=res, aovs=True)
        metrics = refract.metrics(frame, reference)
        flip = refract.error_maps(frame, reference)["flip"]
        axes[0, column].imshow(frame.srgb8())
        axes[0, column].set_title(f"{method} ({frame.timing['ms']:.1f} ms)")
        image = axes[1, column].imshow(np.where(covered, flip, np.nan), cmap="magma", vmin=0, vmax=1)
        axes[1, column].set_title(f"FLIP, mean {metrics['flip_mean']:.3f}")
        rows.append(
            [
                method,
                f"{metrics['flip_mean']:.3f}",
                f"{metrics['t2_angle_deg_mean']:.2f}",
                "-" if metrics["p2_error_rel_mean"] is None else f"{metrics['p2_error_rel_mean']:.3f}",
                f"{metrics['ms_per_frame']:.1f}",
            ]
        )
    for ax in axes.flat:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.colorbar(image, ax=axes[1, :].tolist(), shrink=0.9, label="FLIP (0: identical)")
    table = fig.add_subplot(grid[2, :])
    table.axis("off")
    table.table(
        cellText=rows,
        colLabels=["method", "FLIP mean", "T2 error (deg)", "P2 error (rel. diam.)", "ms / frame (CPU)"],
        loc="center",
        cellLoc="center",
    ).scale(1, 1.4)
    fig.suptitle(f"{scene.name}, IOR {scene.ior:g}, {res[0]}x{res[1]}: against the exact reference")
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    for row in rows:
        print("  ".join(row))


if __name__ == "__main__":
    main()
