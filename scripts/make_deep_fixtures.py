#!/usr/bin/env python3
"""Writes the deep OpenEXR test fixtures of tests/stacks/deep_import.rs into tests/fixtures/deep/.

A 24x20 light view (orthographic, light travelling along -y, Z = distance along the light)
of three analytic planes: a ground Z = 20 + 0.15 u + 0.05 v everywhere, a box top Z = 12 over
x in [4, 12), y in [3, 10), and a tilted card Z = 6 + 0.2 u - 0.1 v over x in [8, 20),
y in [6, 16) (u, v = pixel centre). Extra samples exercise the importer: a near-duplicate of the
box top (merged), volumetric ground samples (ZBack = Z + 0.5) for x >= 20, card samples of
alpha 0.5 where (x + y) % 7 == 0 (kept) and fully transparent samples (alpha 0, dropped) at
Z = 5 for x, y < 3.

Files (sidecars <name>.json next to each):
  deep_none.exr, deep_rle.exr, deep_zips.exr   the same deep image, compression NONE/RLE/ZIPS
  deep_unsorted.exr                            pixel (5, 4) with its samples back to front
  deep_nan.exr                                 pixel (2, 7) with a NaN Z
  layered/deep_ref.exr                         the equivalent per-layer stack (docs/stacks.md):
                                               the same layers and depths, analytic slopes

Run: python3 scripts/make_deep_fixtures.py   (needs the OpenEXR Python binding >= 3.3, numpy)
"""
import json
import os

import numpy as np
import OpenEXR

W, H = 24, 20
NEAR, FAR = 4.0, 26.0
TOL = 1e-6  # render::DEDUP_EPS
OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "fixtures", "deep")


def samples(x, y):
    """The samples of pixel (x, y): list of (Z, ZBack, A, dz/du, dz/dv) in world units."""
    u, v = x + 0.5, y + 0.5
    s = []
    zg = 20 + 0.15 * u + 0.05 * v
    s.append((zg, zg + (0.5 if x >= 20 else 0.0), 1.0, 0.15, 0.05))
    if 4 <= x < 12 and 3 <= y < 10:
        s.append((12.0, 12.0, 1.0, 0.0, 0.0))
        if x < 6 and y < 5:
            s.append((12.0 + 2e-6, 12.0 + 2e-6, 1.0, 0.0, 0.0))  # within the tolerance: merged
    if 8 <= x < 20 and 6 <= y < 16:
        zc = 6 + 0.2 * u - 0.1 * v
        s.append((zc, zc, 0.5 if (x + y) % 7 == 0 else 1.0, 0.2, -0.1))
    if x < 3 and y < 3:
        s.append((5.0, 5.0, 0.0, 0.0, 0.0))  # transparent: dropped
    s.sort(key=lambda t: np.float32(t[0]))
    return s


def deep_channels(unsorted=None, nan=None):
    Z = np.empty((H, W), dtype=object)
    ZB = np.empty((H, W), dtype=object)
    A = np.empty((H, W), dtype=object)
    for y in range(H):
        for x in range(W):
            s = samples(x, y)
            if (x, y) == unsorted:
                s = s[::-1]
            z = np.array([t[0] for t in s], dtype=np.float32)
            if (x, y) == nan:
                z[0] = np.nan
            Z[y, x] = z
            ZB[y, x] = np.array([t[1] for t in s], dtype=np.float32)
            A[y, x] = np.array([t[2] for t in s], dtype=np.float16)
    return {"Z": Z, "ZBack": ZB, "A": A}


def write_deep(name, compression, **kw):
    header = {"compression": compression, "type": OpenEXR.deepscanline}
    OpenEXR.File(header, deep_channels(**kw)).write(os.path.join(OUT, name + ".exr"))
    side = {"scene": "deep", "view": "light0", "light_dir": [0.0, -1.0, 0.0],
            "near": NEAR, "far": FAR, "texel_size": 1.0}
    with open(os.path.join(OUT, name + ".json"), "w") as f:
        json.dump(side, f, indent=2)
        f.write("\n")


def write_reference():
    """The per-layer stack the deep image must import to (layers, depths); slopes analytic."""
    per = []
    for y in range(H):
        for x in range(W):
            layers, last = [], -np.inf
            for (z, _zb, a, su, sv) in samples(x, y):
                if a == 0.0:
                    continue
                d = (float(np.float32(z)) - NEAR) / (FAR - NEAR)
                if d - last <= TOL:
                    continue
                last = d
                layers.append((np.float32(d), su / (FAR - NEAR), sv / (FAR - NEAR)))
            per.append(layers)
    L = max(len(p) for p in per)
    depth = np.full((L, H, W), np.inf, dtype=np.float32)
    dzdu = np.zeros((L, H, W), dtype=np.float32)
    dzdv = np.zeros((L, H, W), dtype=np.float32)
    for t, layers in enumerate(per):
        y, x = divmod(t, W)
        for l, (d, su, sv) in enumerate(layers):
            depth[l, y, x], dzdu[l, y, x], dzdv[l, y, x] = d, su, sv
    chans = {}
    for l in range(L):
        for q, a in (("Z", depth), ("dzdu", dzdu), ("dzdv", dzdv)):
            chans[f"layer{l:03d}.{q}"] = np.ascontiguousarray(a[l])
    d = os.path.join(OUT, "layered")
    os.makedirs(d, exist_ok=True)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, chans).write(os.path.join(d, "deep_ref.exr"))
    meta = {"scene": "deep", "view": "light0", "light_dir": [0.0, -1.0, 0.0],
            "near": NEAR, "far": FAR, "width": W, "height": H, "layers": L, "texel_size": 1.0}
    with open(os.path.join(d, "deep_ref.json"), "w") as f:
        json.dump(meta, f, indent=2)
        f.write("\n")


def main():
    os.makedirs(OUT, exist_ok=True)
    write_deep("deep_none", OpenEXR.NO_COMPRESSION)
    write_deep("deep_rle", OpenEXR.RLE_COMPRESSION)
    write_deep("deep_zips", OpenEXR.ZIPS_COMPRESSION)
    write_deep("deep_unsorted", OpenEXR.NO_COMPRESSION, unsorted=(5, 4))
    write_deep("deep_nan", OpenEXR.NO_COMPRESSION, nan=(2, 7))
    write_reference()


if __name__ == "__main__":
    main()
