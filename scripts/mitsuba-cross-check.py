#!/usr/bin/env python3
"""Cross-check refract's exact reference against Mitsuba 3, as a user would.

For every case: write a refract scene file, export it with `refract export` (the meshes exactly
as refract renders them: normalised, transformed, with refract's vertex normals), render it
with `refract render --method reference --param mode=full` and with Mitsuba 3 (`scalar_rgb`,
path tracer, dielectric or conductor, envmap, box filter) twice with different seeds, and print the mean
relative difference and the PSNR of ours against Mitsuba beside Mitsuba against itself (its
noise floor at that sample count).

    pip install mitsuba numpy
    cargo build --release
    python3 scripts/mitsuba-cross-check.py [--res 128] [--spp 256] [--cases sphere,cow]

Needs ../shared/data (the meshes and HDRIs). Not run in CI: it takes minutes.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(ROOT, "..", "shared", "data")
REFRACT = os.path.join(ROOT, "target", "release", "refract")

# name: (mesh, ior, environment map, extra TOML for [refractor], camera TOML)
# (The built-in scenes' geometry, in real HDRIs instead of the procedural sky, which Mitsuba
# does not have. `cow-sun` is a stress case: esplanade.exr has a sun of ~30,000, so both
# renderers are noisy there.)
CASES = {
    "sphere": ("builtin:sphere", 1.5, "venice.exr", "", ""),
    "torus": ("builtin:torus", 1.33, "apartment.exr", "rotate_deg = [60.0, 0.0, 0.0]\n", ""),
    "lens": ("builtin:lens", 1.5, "city.exr", "", "[camera]\neye = [0.0, 0.3, 3.0]\n"),
    "cow": ("meshes/cow.obj", 1.5, "forest.exr", "", ""),
    "horse": ("meshes/horse.obj", 1.5, "apartment.exr", "", ""),
    "cow-sun": ("meshes/cow.obj", 1.5, "esplanade.exr", "", ""),
    # Conductors (issue 17): refract's exact conductor Fresnel vs Mitsuba's `conductor`.
    "copper": ("builtin:sphere", 1.5, "venice.exr", "material = \"copper\"\n", ""),
    "gold-torus": ("builtin:torus", 1.5, "apartment.exr", "material = \"gold\"\nrotate_deg = [60.0, 0.0, 0.0]\n", ""),
}


def scene_toml(case):
    mesh, ior, envmap, refractor_extra, camera = CASES[case]
    mesh = mesh if mesh.startswith("builtin:") else os.path.join(DATA, mesh)
    return (
        f"{camera}\n[environment]\nfile = \"{os.path.join(DATA, 'envmaps', envmap)}\"\n\n"
        f"[refractor]\nmesh = \"{mesh}\"\nior = {ior}\n{refractor_extra}"
    )


def run(args):
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)


def bsdf(desc):
    """A refractor's BSDF: Mitsuba's smooth `dielectric` between its medium and the one around it
    (`int_ior`/`ext_ior`, as refract's scene.json gives them), or its smooth `conductor` with the
    RGB complex index refract used."""
    conductor = desc.get("conductor")
    if conductor is None:
        return {
            "type": "dielectric",
            "int_ior": desc.get("int_ior", desc.get("ior")),
            "ext_ior": desc.get("ext_ior", 1.0),
        }
    return {
        "type": "conductor",
        "eta": {"type": "rgb", "value": conductor["eta"]},
        "k": {"type": "rgb", "value": conductor["k"]},
    }


def absorbing(desc):
    return any(r.get("attenuation") for r in desc.get("refractors") or [])


def refractor_shapes(exported, desc):
    """Every refractor of scene.json as an OBJ shape (older exports: the one `refractor`). An
    absorbing medium is Mitsuba's `homogeneous` medium (sigma_t = refract's coefficient, albedo
    0) inside the shape and, for a refractor within it, outside that one."""
    refractors = desc.get("refractors") or [
        {"file": desc["refractor"], "ior": desc["ior"], "conductor": desc.get("conductor")}
    ]

    def medium(index):
        if index is None or refractors[index].get("attenuation") is None:
            return None
        sigma = refractors[index]["attenuation"]["coefficient"]
        return {
            "type": "homogeneous",
            "sigma_t": {"type": "rgb", "value": sigma},
            "albedo": 0.0,
        }

    shapes = {}
    for k, r in enumerate(refractors):
        shape = {
            "type": "obj",
            "filename": os.path.join(exported, r["file"]),
            "face_normals": False,
            "bsdf": bsdf(r),
        }
        if medium(k) is not None:
            shape["interior"] = medium(k)
        if medium(r.get("within")) is not None:
            shape["exterior"] = medium(r.get("within"))
        shapes["refractor" if k == 0 else f"refractor-{k}"] = shape
    return shapes


def mitsuba_render(mi, exported, res, spp, seed):
    with open(os.path.join(exported, "scene.json")) as f:
        desc = json.load(f)
    cam = desc["camera"]
    env = desc["environment"]
    assert env["kind"] == "latlong", "the cross-check needs a lat-long environment"
    scene = mi.load_dict(
        {
            "type": "scene",
            # volpath where a refractor absorbs (its media), path otherwise.
            "integrator": {
                "type": "volpath" if absorbing(desc) else "path",
                "max_depth": 65,
                "rr_depth": 65,
            },
            "sensor": {
                "type": "perspective",
                "fov": cam["fov_y_deg"],
                "fov_axis": "y",
                "near_clip": 0.05,
                "far_clip": 100.0,
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=cam["eye"], target=cam["target"], up=cam["up"]
                ),
                "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
                "film": {
                    "type": "hdrfilm",
                    "width": res,
                    "height": res,
                    "rfilter": {"type": "box"},
                    "pixel_format": "rgb",
                },
            },
            "environment": {
                "type": "envmap",
                "filename": env["file"],
                "scale": env["intensity"],
            },
            **refractor_shapes(exported, desc),
        }
    )
    return mi.render(scene, seed=seed)


def load_exr_rgb(mi, path):
    import numpy as np

    # refract's EXRs hold R, G, B beside the AOV layers; the un-prefixed channels are the root.
    root = dict(mi.Bitmap(path).split())["<root>"]
    names = [field.name for field in root.struct_()]
    data = np.array(root)
    return np.stack([data[..., names.index(c)] for c in "RGB"], axis=-1)


def compare(a, b):
    """Mean |a - b| / mean(b), and PSNR of a against b with the peak of b."""
    import numpy as np

    diff = np.abs(a - b)
    relative = diff.mean() / max(b.mean(), 1e-12)
    mse = float((diff**2).mean())
    peak = float(b.max())
    psnr = 10.0 * math.log10(peak * peak / max(mse, 1e-30))
    return relative, psnr


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", type=int, default=128, help="a multiple of 8")
    parser.add_argument("--spp", type=int, default=256)
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument(
        "--interface", default="shading", choices=["shading", "geometric"],
        help="refract's interface rule (shading is Mitsuba's)",
    )
    args = parser.parse_args()
    if not os.path.isdir(DATA):
        sys.exit(f"{DATA} not found: the cross-check needs the shared meshes and HDRIs")
    if not os.path.isfile(REFRACT):
        sys.exit(f"{REFRACT} not found: run `cargo build --release` first")
    import mitsuba as mi
    import numpy as np

    mi.set_variant("scalar_rgb")
    print(
        f"{args.res}², {args.spp} spp, refract reference (full, depth 64, interface={args.interface}) "
        "vs Mitsuba 3 (path, max_depth 65, seeds 1 and 2)"
    )
    # Ours has almost no noise (deterministic Fresnel splitting; only the pixel area is
    # sampled), Mitsuba's two renders have the same noise sigma. Unbiased, ours vs the mean of
    # the two renders (noise sigma / sqrt 2) matches half their difference (also sigma / sqrt 2):
    # the "balanced" columns compare like with like.
    # Mitsuba's per-pixel noise is skewed (rare bright paths), which the balanced pair does not
    # fully cancel; averaged over 8 x 8 blocks the noise shrinks and a bias would remain.
    print(
        f"{'scene':<8} {'ours vs mi1':>12} {'mi2 vs mi1':>11} {'PSNR ours':>10} {'PSNR mi':>8}"
        f" {'balanced: ours vs mean(mi)':>27} {'(mi1-mi2)/2':>12}"
        f" {'8x8 blocks: ours vs mean(mi)':>29} {'(mi1-mi2)/2':>12}"
    )
    for case in args.cases.split(","):
        with tempfile.TemporaryDirectory() as tmp:
            toml = os.path.join(tmp, f"{case}.toml")
            with open(toml, "w") as f:
                f.write(scene_toml(case))
            exported = os.path.join(tmp, "export")
            run([REFRACT, "export", toml, "--out", exported])
            ours_path = os.path.join(tmp, "ours.exr")
            run([
                REFRACT, "render", toml, "--method", "reference", "--res", str(args.res),
                "--param", "mode=full", "--param", "depth=64", "--param", f"spp={args.spp}",
                "--param", f"interface={args.interface}", "--out", ours_path,
            ])
            ours = load_exr_rgb(mi, ours_path)
            first = np.array(mitsuba_render(mi, exported, args.res, args.spp, 1))
            second = np.array(mitsuba_render(mi, exported, args.res, args.spp, 2))
            ours_rel, ours_psnr = compare(ours, first)
            floor_rel, floor_psnr = compare(second, first)
            mean = 0.5 * (first + second)
            balanced = np.abs(ours - mean).mean() / mean.mean()
            half = np.abs(0.5 * (first - second)).mean() / mean.mean()
            blocks = lambda img: img.reshape(args.res // 8, 8, args.res // 8, 8, 3).mean(axis=(1, 3))
            block_balanced = np.abs(blocks(ours) - blocks(mean)).mean() / mean.mean()
            block_half = np.abs(0.5 * (blocks(first) - blocks(second))).mean() / mean.mean()
            print(
                f"{case:<8} {100 * ours_rel:>11.2f}% {100 * floor_rel:>10.2f}% {ours_psnr:>10.2f}"
                f" {floor_psnr:>8.2f} {100 * balanced:>26.2f}% {100 * half:>11.2f}%"
                f" {100 * block_balanced:>28.2f}% {100 * block_half:>11.2f}%",
                flush=True,
            )


if __name__ == "__main__":
    main()
