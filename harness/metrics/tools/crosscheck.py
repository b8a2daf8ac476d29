#!/usr/bin/env python3
"""Cross-check tessera-metrics against scikit-image and NVIDIA's flip-evaluator.

For: proving the crate's agreement claims (PSNR 1e-6, SSIM 1e-5, FLIP pooled 1e-4) on
generated, rendered-like image pairs. Not for: CI (needs `pip install flip-evaluator
scikit-image` and a release build; run it by hand and copy the summary into the README).

Usage (from the workspace root):
    python3 harness/metrics/tools/crosscheck.py [--out DIR] [--big]

It writes image pairs and a manifest to DIR, runs the `crosscheck` example of tessera-metrics on
them, computes the same metrics with the reference implementations and prints the largest
absolute differences. Exits 1 if any tolerance is exceeded.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import imageio.v3 as iio
import flip_evaluator as flip
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

TOL = {"psnr": 1e-6, "ssim": 1e-5, "flip": 1e-4}
PPD = 67.0


def scene(w, h, seed, hdr=False):
    """A rendered-like linear RGB image: sky gradient, lit spheres, hard-edged boxes, texture."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    u, v = x / w, y / h
    img = np.empty((h, w, 3))
    img[..., 0] = 0.25 + 0.35 * v
    img[..., 1] = 0.45 + 0.3 * v
    img[..., 2] = 0.9 - 0.2 * v
    ground = v > 0.6
    checker = ((np.floor(u * 16) + np.floor(v * 12)) % 2)[..., None]
    img[ground] = (0.15 + 0.35 * checker[ground]) * np.array([0.8, 0.75, 0.6])
    for _ in range(5):
        cx, cy, r = rng.uniform(0.1, 0.9), rng.uniform(0.3, 0.7), rng.uniform(0.05, 0.15)
        col = rng.uniform(0.1, 1.0, 3)
        d2 = ((u - cx) * w / h) ** 2 + (v - cy) ** 2
        inside = d2 < r * r
        nz = np.sqrt(np.clip(1 - d2 / (r * r), 0, 1))
        lit = 0.15 + 0.85 * np.clip(0.5 * nz + 0.5 * ((cx - u) * w / h + (cy - v)) / r, 0, 1)
        spec = np.clip(nz, 0, 1) ** 40 * (4.0 if hdr else 0.6)
        img[inside] = (col * lit[..., None] + spec[..., None])[inside]
    for _ in range(3):
        x0, y0 = rng.uniform(0, 0.8), rng.uniform(0.4, 0.8)
        box = (u > x0) & (u < x0 + 0.12) & (v > y0) & (v < y0 + 0.15)
        img[box] = rng.uniform(0.05, 0.9, 3)
    img += rng.normal(0, 0.01, img.shape) * (1 + 3 * ground[..., None])
    if hdr:
        sun = ((u - 0.8) ** 2 + (v - 0.15) ** 2) < 0.002
        img[sun] = 60.0
        img[..., :] *= 1.0 + 3.0 * (v < 0.3)[..., None]
    return np.clip(img, 0, None)


def to_srgb8(lin):
    c = np.clip(lin, 0, 1)
    s = np.where(c <= 0.0031308, c * 12.92, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.floor(s * 255 + 0.5).astype(np.uint8)


def ldr_variants(ref, seed):
    rng = np.random.default_rng(seed)
    f = ref.astype(np.float64)
    out = {}
    out["noise4"] = np.clip(f + rng.normal(0, 4, f.shape), 0, 255)
    # Checkerboard reconstruction: half the pixels rebuilt from horizontal neighbours.
    cb = f.copy()
    yy, xx = np.mgrid[0:f.shape[0], 0:f.shape[1]]
    holes = ((xx + yy) % 2 == 1)
    avg = 0.5 * (np.roll(f, 1, axis=1) + np.roll(f, -1, axis=1))
    cb[holes] = avg[holes]
    out["checkerboard"] = cb
    k = np.ones(3) / 3
    blur = np.apply_along_axis(lambda r: np.convolve(r, k, mode="same"), 1, f)
    out["blur"] = np.apply_along_axis(lambda c: np.convolve(c, k, mode="same"), 0, blur)
    out["shift1"] = np.roll(f, 1, axis=1)
    out["quant5"] = np.floor(f / 8) * 8 + 4
    out["other"] = f[::-1, ::-1] * 0.7 + 40
    return {k: np.clip(np.round(v), 0, 255).astype(np.uint8) for k, v in out.items()}


def flip_pool(m):
    """FLIP's FlipPool, in f32 like pooling.h: mean and getPercentile(p, weighted=True)."""
    flat = m.ravel().astype(np.float32)
    total = np.cumsum(flat, dtype=np.float32)[-1]
    srt = np.sort(flat)
    run = np.cumsum(srt, dtype=np.float32)
    res = {"mean_f64": float(np.mean(flat, dtype=np.float64)), "max": float(flat.max())}
    for p, key in [(0.5, "p50"), (0.95, "p95"), (0.99, "p99")]:
        idx = np.nonzero(run > np.float32(p) * total)[0]
        res[key] = float(srt[idx[0]]) if len(idx) else 0.0
    return res


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=None)
    ap.add_argument("--big", action="store_true", help="add a 1920x1080 pair")
    args = ap.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="tessera-crosscheck-")
    os.makedirs(out, exist_ok=True)

    manifest, expected = [], {}
    sizes = [(320, 240, 1), (257, 131, 2)] + ([(1920, 1080, 3)] if args.big else [])
    for w, h, seed in sizes:
        ref = to_srgb8(scene(w, h, seed))
        iio.imwrite(os.path.join(out, f"ref_{w}x{h}.png"), ref)
        for name, test in ldr_variants(ref, seed).items():
            pair = f"{name}_{w}x{h}"
            iio.imwrite(os.path.join(out, pair + ".png"), test)
            manifest.append({"name": pair, "kind": "ldr", "reference": f"ref_{w}x{h}.png",
                             "test": pair + ".png", "width": w, "height": h})
            expected[pair] = (ref, test)
    hdr_pairs = {}
    for w, h, seed in [(192, 128, 4)]:
        ref = scene(w, h, seed, hdr=True).astype(np.float32)
        rng = np.random.default_rng(seed)
        tests = {
            "hdr_noise": ref * (1 + rng.normal(0, 0.05, ref.shape)).astype(np.float32),
            "hdr_exposure": ref * np.float32(1.1),
            "hdr_fireflies": np.where(rng.random(ref.shape[:2])[..., None] < 0.002, 50.0, ref),
        }
        dark = ref.copy()
        dark[: h * 2 // 3] = 0.0  # more than half black: zero median luminance
        tests_dark = {"hdr_zero_median": (dark, np.clip(dark * 1.05 + 0.001, 0, None))}
        for name, test in tests.items():
            hdr_pairs[name] = (ref, np.clip(test, 0, None).astype(np.float32))
        for name, (r, t) in tests_dark.items():
            hdr_pairs[name] = (r.astype(np.float32), t.astype(np.float32))
        for name, (r, t) in hdr_pairs.items():
            r.astype("<f4").tofile(os.path.join(out, name + ".ref.f32"))
            t.astype("<f4").tofile(os.path.join(out, name + ".test.f32"))
            manifest.append({"name": name, "kind": "hdr", "reference": name + ".ref.f32",
                             "test": name + ".test.f32", "width": w, "height": h})
    with open(os.path.join(out, "manifest.json"), "w") as f:
        json.dump(manifest, f, indent=1)

    cmd = ["cargo", "run", "--quiet", "--release", "-p", "tessera-metrics", "--example",
           "crosscheck", "--", os.path.join(out, "manifest.json")]
    ours = {r["name"]: r for r in json.loads(subprocess.check_output(cmd))}

    # flip: our mean vs the mean flip-evaluator reports (both accumulated in f32), our exact
    # (f64) mean vs the f64 mean of flip-evaluator's map, and FlipPool's weighted percentiles
    # (f32 running sums, as pooling.h) of flip-evaluator's map vs ours; map px: per-pixel.
    worst = {"psnr": 0.0, "ssim": 0.0, "flip": 0.0, "flip_map_px": 0.0}
    print(f"{'pair':<22} {'dPSNR':>9} {'dPSNRy':>9} {'dSSIM':>9} {'dSSIMy':>9} "
          f"{'dFexact':>9} {'dFmean':>9} {'dFp50':>9} {'dFp95':>9} {'dFp99':>9} {'dFmax':>9} {'map px':>9}")
    for e in manifest:
        name = e["name"]
        o = ours[name]
        if e["kind"] == "ldr":
            ref, test = expected[name]
            luma = lambda a: 0.299 * a[..., 0].astype(np.float64) + 0.587 * a[..., 1] + 0.114 * a[..., 2]
            ps = peak_signal_noise_ratio(ref, test, data_range=255)
            psy = peak_signal_noise_ratio(luma(ref), luma(test), data_range=255)
            kw = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=255)
            ss = structural_similarity(ref, test, channel_axis=2, **kw)
            ssy = structural_similarity(luma(ref), luma(test), **kw)
            fmap, fmean, _ = flip.evaluate(ref.astype(np.float32) / np.float32(255),
                                           test.astype(np.float32) / np.float32(255), "LDR",
                                           applyMagma=False, parameters={"ppd": PPD})
            d = [abs(o["psnr_rgb"] - ps), abs(o["psnr_luma"] - psy),
                 abs(o["ssim_rgb"] - ss), abs(o["ssim_luma"] - ssy)]
            worst["psnr"] = max(worst["psnr"], d[0], d[1])
            worst["ssim"] = max(worst["ssim"], d[2], d[3])
        else:
            r, t = hdr_pairs[name]
            fmap, fmean, params = flip.evaluate(r, t, "HDR", applyMagma=False,
                                                parameters={"ppd": PPD})
            rng_o = o["range"]
            assert abs(rng_o["start"] - params["startExposure"]) < 1e-5, (rng_o, params)
            assert abs(rng_o["stop"] - params["stopExposure"]) < 1e-5, (rng_o, params)
            assert rng_o["count"] == params["numExposures"], (rng_o, params)
            d = [float("nan")] * 4
        pooled = flip_pool(np.asarray(fmap))
        of = o["flip"]
        fd = [abs(of["exact_mean"] - pooled["mean_f64"]), abs(of["mean"] - fmean),
              abs(of["p50"] - pooled["p50"]),
              abs(of["p95"] - pooled["p95"]), abs(of["p99"] - pooled["p99"]),
              abs(of["max"] - pooled["max"])]
        worst["flip"] = max([worst["flip"]] + fd)
        our_map = np.fromfile(os.path.join(out, name + ".flipmap.f32"), dtype="<f4")
        px = float(np.max(np.abs(our_map - np.asarray(fmap, dtype=np.float32).ravel())))
        worst["flip_map_px"] = max(worst["flip_map_px"], px)
        print(f"{name:<22} " + " ".join(f"{v:9.1e}" for v in d + fd + [px]))
    print()
    print("largest |ours - reference|: " + ", ".join(f"{k} {v:.2e}" for k, v in worst.items()))
    ok = all(worst[k] <= TOL[k] for k in TOL)
    print("within tolerances (PSNR 1e-6, SSIM 1e-5, FLIP pooled 1e-4):", ok)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
