#!/usr/bin/env python3
"""Counts the eight-lane code of the workspace (issue 48's measure): the non-blank, non-comment
lines outside `#[cfg(test)]` of the lane modules (refract-core's lanes.rs, kernel_x8.rs,
nearby_geometry_x8.rs), of every other function whose name ends in `_x8`, and of real.rs's
eight-lane trait implementations (`impl ... for F32x8` / `Vec3x8` / `Mask`).

Usage: scripts/lane-lines.py [ROOT]   (prints one line per source and the total)
"""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
LANE_FILES = ["lanes.rs", "kernel_x8.rs", "nearby_geometry_x8.rs"]


def code_lines(lines):
    """The lines that are code: not blank, not a comment."""
    return [l for l in lines if l.strip() and not l.strip().startswith("//")]


def strip_tests(text):
    """The text before the first `#[cfg(test)]` module."""
    cut = text.find("#[cfg(test)]")
    return text if cut < 0 else text[:cut]


def block_at(lines, start):
    """The lines of the item starting at `start`, through its matching closing brace."""
    depth, seen, out = 0, False, []
    for line in lines[start:]:
        out.append(line)
        code = line.split("//")[0]
        depth += code.count("{") - code.count("}")
        seen = seen or "{" in code
        if seen and depth <= 0:
            break
        if not seen and code.rstrip().endswith(";"):
            break
    return out


counts = {}
core = root / "crates/refract-core/src"
for name in LANE_FILES:
    path = core / name
    if path.exists():
        counts[str(path.relative_to(root))] = len(code_lines(strip_tests(path.read_text()).splitlines()))

lane_impl = re.compile(r"^\s*impl(<[^>]*>)?\s+[\w:<>, ]+\s+for\s+(F32x8|Vec3x8|Mask)\b")
x8_fn = re.compile(r"^\s*(pub(\([^)]*\))?\s+)?(const\s+)?(unsafe\s+)?fn\s+\w+_x8\b")
for path in sorted(root.glob("crates/*/src/**/*.rs")):
    if path.name in LANE_FILES and path.parent == core:
        continue
    lines = strip_tests(path.read_text()).splitlines()
    total, i = 0, 0
    while i < len(lines):
        line = lines[i]
        is_real = path.name == "real.rs" and lane_impl.match(line)
        if is_real or x8_fn.match(line):
            block = block_at(lines, i)
            total += len(code_lines(block))
            i += len(block)
        else:
            i += 1
    if total:
        counts[str(path.relative_to(root))] = total

for name, n in counts.items():
    print(f"{n:5d}  {name}")
print(f"{sum(counts.values()):5d}  total")
