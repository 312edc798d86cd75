#!/usr/bin/env python3
"""Read a groutready .vtu with meshio and check its contents.

Usage:
    python3 tests/vtu_check.py FILE.vtu|DIR [--points N] [--cells M] \
        [--point-field NAME[:COMPONENTS]]... [--cell-field NAME[:COMPONENTS]]... \
        [--range NAME:LO:HI]...

A DIR checks every .vtu in it (counts are then not compared). --range checks
that a point field is finite and within [LO, HI] on every node a cell uses.

Checks: the file parses, it holds exactly N points and M hexahedra (and no
other cell type), connectivity indices are in range, every hexahedron has a
positive volume (the VTK node order is respected), the listed point/cell
fields exist with one value (or COMPONENTS values) per point/cell, and the
always-written cell fields `block` and `lift` are there.
Needs: pip install meshio numpy. Exit code 0 = all good, 1 = a check failed.
"""

import argparse
import glob
import os
import sys

import meshio
import numpy as np


def field_spec(text):
    name, _, comps = text.partition(":")
    return name, int(comps) if comps else 1


def hex_volumes(points, hexes):
    """Volumes by 2x2x2 Gauss quadrature of the trilinear map (exact)."""
    ref = np.array(
        [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
         [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
    x = points[hexes]  # (n, 8, 3)
    g = 1.0 / np.sqrt(3.0)
    vol = np.zeros(len(hexes))
    for a in (-g, g):
        for b in (-g, g):
            for c in (-g, g):
                d = np.stack([
                    0.125 * ref[:, 0] * (1 + ref[:, 1] * b) * (1 + ref[:, 2] * c),
                    0.125 * ref[:, 1] * (1 + ref[:, 0] * a) * (1 + ref[:, 2] * c),
                    0.125 * ref[:, 2] * (1 + ref[:, 0] * a) * (1 + ref[:, 1] * b),
                ], axis=1)  # (8, 3)
                jac = np.einsum("nai,aj->nij", x, d)
                vol += np.linalg.det(jac)
    return vol


def range_spec(text):
    name, lo, hi = text.split(":")
    return name, float(lo), float(hi)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file")
    ap.add_argument("--points", type=int)
    ap.add_argument("--cells", type=int)
    ap.add_argument("--point-field", action="append", default=[], type=field_spec)
    ap.add_argument("--cell-field", action="append", default=[], type=field_spec)
    ap.add_argument("--range", action="append", default=[], type=range_spec)
    args = ap.parse_args()
    if os.path.isdir(args.file):
        files = sorted(glob.glob(os.path.join(args.file, "*.vtu")))
        if not files:
            print(f"{args.file}: no .vtu files", file=sys.stderr)
            return 1
        worst = 0
        for f in files:
            worst = max(worst, check(f, args))
        return worst
    return check(args.file, args)


def check(path, args):
    errors = []
    mesh = meshio.read(path)
    n_points = len(mesh.points)
    if args.points is not None and n_points != args.points:
        errors.append(f"{n_points} points, expected {args.points}")
    types = [block.type for block in mesh.cells]
    if types != ["hexahedron"]:
        errors.append(f"cell blocks {types}, expected only hexahedron")
    hexes = np.concatenate([b.data for b in mesh.cells if b.type == "hexahedron"]) \
        if "hexahedron" in types else np.zeros((0, 8), dtype=int)
    if args.cells is not None and len(hexes) != args.cells:
        errors.append(f"{len(hexes)} hexahedra, expected {args.cells}")
    if len(hexes) and (hexes.min() < 0 or hexes.max() >= n_points):
        errors.append("connectivity index out of range")
    elif len(hexes):
        vol = hex_volumes(np.asarray(mesh.points, dtype=float), hexes)
        if not (vol > 0).all():
            errors.append(f"{int((vol <= 0).sum())} hexahedra with volume <= 0")
        else:
            print(f"volume {vol.sum():.6g} m^3, smallest hex {vol.min():.6g} m^3")

    for name, comps in args.point_field:
        if name not in mesh.point_data:
            errors.append(f"point field {name!r} missing (have {sorted(mesh.point_data)})")
            continue
        a = np.asarray(mesh.point_data[name])
        if comps == 1 and a.ndim == 2 and a.shape[1] == 1:
            a = a[:, 0]
        want = (n_points,) if comps == 1 else (n_points, comps)
        if a.shape != want:
            errors.append(f"point field {name!r} has shape {a.shape}, expected {want}")
    cell_fields = list(args.cell_field) + [("block", 1), ("lift", 1)]
    for name, comps in cell_fields:
        if name not in mesh.cell_data:
            errors.append(f"cell field {name!r} missing (have {sorted(mesh.cell_data)})")
            continue
        a = np.concatenate([np.asarray(x) for x in mesh.cell_data[name]])
        if comps == 1 and a.ndim == 2 and a.shape[1] == 1:
            a = a[:, 0]
        want = (len(hexes),) if comps == 1 else (len(hexes), comps)
        if a.shape != want:
            errors.append(f"cell field {name!r} has shape {a.shape}, expected {want}")

    used = np.unique(hexes) if len(hexes) else np.zeros(0, dtype=int)
    for name, lo, hi in args.range:
        if name not in mesh.point_data:
            errors.append(f"point field {name!r} missing for the range check")
            continue
        a = np.asarray(mesh.point_data[name]).reshape(n_points, -1)[used]
        if not np.isfinite(a).all():
            errors.append(f"point field {name!r} is not finite on {int((~np.isfinite(a)).sum())} used nodes")
        elif a.min() < lo or a.max() > hi:
            errors.append(f"point field {name!r} spans [{a.min():.4g}, {a.max():.4g}], outside [{lo}, {hi}]")
        else:
            print(f"{path}: {name} in [{a.min():.4g}, {a.max():.4g}] on {len(used)} used nodes")

    if errors:
        for e in errors:
            print(f"{path}: {e}", file=sys.stderr)
        return 1
    print(f"{path}: OK ({n_points} points, {len(hexes)} hexahedra, "
          f"point fields {sorted(mesh.point_data)}, cell fields {sorted(mesh.cell_data)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
