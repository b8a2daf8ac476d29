#!/usr/bin/env python3
"""Cross-check tessera-metrics' ColorVideoVDP (the `colorvideovdp` crate behind `cvvdp()`) against
the reference implementation, PyPI `cvvdp` 0.5.7 (PyTorch).

For: proving that JOD, per-frame JOD and the perceptual-flicker numbers equal the reference's
(claim: largest JOD difference <= 0.01) on image pairs and short sequences generated at check time:
noise, blur, a 1-pixel shift, alternating-frame flicker of 1-5 %, a ghost trail; SDR (8-bit sRGB)
and HDR (linear, cd/m2); four display models. Not for: CI (needs PyTorch; run it by hand, e.g. on
the lent GPU machine, and copy the table into the README).

Usage (from the workspace root):
    python3 harness/metrics/tools/crosscheck_cvvdp.py gen DIR        # numpy only
    target/release/examples/cvvdp_crosscheck DIR                    # Rust side -> DIR/rust.json
    python3 harness/metrics/tools/crosscheck_cvvdp.py ref DIR        # needs torch + cvvdp 0.5.7
    python3 harness/metrics/tools/crosscheck_cvvdp.py compare DIR    # table; exit 1 over tolerance
or `... all DIR --rust-bin PATH` for the four steps at once.

Per-frame JOD and the flicker measures are not outputs of the reference: on its side they are
computed from the reference's own `stats["Q_per_ch"]` with its own `lp_norm`, `safe_pow` and
`met2jod`, following the definitions in `src/cvvdp/mod.rs`.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

TOL_JOD = 0.01

# Display models: the name the Rust side parses, and the record the reference loads (None: its
# own display_models.json has it). Custom records use the reference's display_models.json keys.
PAPER = {"name": "paper 27in 4K", "resolution": [3840, 2160], "pixels_per_degree": 76.2,
         "max_luminance": 200, "contrast": 1000, "E_ambient": 250}
DISPLAYS = {
    "standard_4k": ("standard_4k", None),
    "paper_27in_4k": ("paper_27in_4k", PAPER),
    "diag27_0.635m": ("diagonal_inches=27,distance_m=0.635",
                      {"name": "27in at 0.635 m", "resolution": [3840, 2160],
                       "diagonal_size_inches": 27, "viewing_distance_meters": 0.635,
                       "max_luminance": 200, "contrast": 1000, "E_ambient": 250}),
    "standard_hdr_linear": ("standard_hdr_linear", None),
    "paper_hdr_1000": ("base=paper_27in_4k,peak_luminance=1000",
                       dict(PAPER, name="paper 27in 4K, 1000 nit, linear", max_luminance=1000,
                            colorspace="BT.709-linear")),
}


def scene(w, h, seed, t=0.0):
    """Linear RGB, rendered-like: sky gradient, a lit sphere, a checker floor, a box moving with t."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    u, v = x / w, y / h
    img = np.empty((h, w, 3))
    img[..., 0] = 0.25 + 0.35 * v
    img[..., 1] = 0.45 + 0.3 * v
    img[..., 2] = 0.9 - 0.2 * v
    ground = v > 0.6
    checker = ((np.floor(u * 16) + np.floor(v * 12)) % 2)[..., None]
    img[ground] = ((0.15 + 0.35 * checker) * np.array([0.8, 0.75, 0.6]))[ground]
    cx, cy, r = 0.3, 0.45, 0.18
    d2 = ((u - cx) * w / h) ** 2 + (v - cy) ** 2
    inside = d2 < r * r
    nz = np.sqrt(np.clip(1 - d2 / (r * r), 0, 1))
    lit = 0.15 + 0.85 * np.clip(0.5 * nz + 0.5 * ((cx - u) * w / h + (cy - v)) / r, 0, 1)
    img[inside] = (np.array([0.8, 0.3, 0.2]) * lit[..., None] + (nz ** 40)[..., None] * 0.6)[inside]
    bx = 0.5 + 0.03 * t
    box = (u > bx) & (u < bx + 0.15) & (v > 0.3) & (v < 0.55)
    img[box] = [0.2, 0.6, 0.3]
    img += rng.normal(0, 0.004, img.shape)
    return np.clip(img, 0, None)


def blur(img, r=1):
    """Separable box blur of radius r, edge-clamped."""
    out = img
    for axis in (0, 1):
        pad = [(0, 0)] * img.ndim
        pad[axis] = (r, r)
        p = np.pad(out, pad, mode="edge")
        n = img.shape[axis]
        out = sum(np.take(p, range(k, k + n), axis=axis) for k in range(2 * r + 1)) / (2 * r + 1)
    return out


def srgb(lin):
    lin = np.clip(lin, 0, 1)
    enc = np.where(lin <= 0.0031308, lin * 12.92, 1.055 * lin ** (1 / 2.4) - 0.055)
    return np.round(enc * 255).astype(np.uint8)


def video(w, h, n, seed):
    return [scene(w, h, seed, t) for t in range(n)]


def distort(frames, how, rng):
    """The test version of a list of linear frames."""
    if how.startswith("noise"):
        return [f + rng.normal(0, 0.05, f.shape) * f.mean() for f in frames]
    if how.startswith("blur"):
        return [blur(f, int(how[4:] or 1)) for f in frames]
    if how == "shift":
        return [np.roll(f, 1, axis=1) for f in frames]
    if how.startswith("flicker"):
        a = float(how[7:]) / 100
        return [f * (1 + a if i % 2 == 0 else 1 - a) for i, f in enumerate(frames)]
    if how == "ghost":
        out, prev = [], None
        for f in frames:
            prev = f if prev is None else 0.6 * f + 0.4 * prev
            out.append(prev)
        return out
    raise ValueError(how)


# (name, kind, display key, frames, fps, distortion)
CASES = [
    ("img-noise", "srgb", "standard_4k", 1, 0, "noise"),
    ("img-blur", "srgb", "standard_4k", 1, 0, "blur1"),
    ("img-shift", "srgb", "standard_4k", 1, 0, "shift"),
    ("img-noise-paper", "srgb", "paper_27in_4k", 1, 0, "noise"),
    ("img-blur-diag", "srgb", "diag27_0.635m", 1, 0, "blur2"),
    ("vid-flicker1", "srgb", "standard_4k", 12, 30, "flicker1"),
    ("vid-flicker3", "srgb", "standard_4k", 12, 30, "flicker3"),
    ("vid-flicker5-paper-60fps", "srgb", "paper_27in_4k", 20, 60, "flicker5"),
    ("vid-ghost", "srgb", "standard_4k", 12, 30, "ghost"),
    ("vid-ghost-paper", "srgb", "paper_27in_4k", 12, 60, "ghost"),
    ("vid-noise-diag", "srgb", "diag27_0.635m", 10, 30, "noise"),
    ("vid-blur", "srgb", "standard_4k", 10, 30, "blur1"),
    ("vid-shift", "srgb", "standard_4k", 10, 30, "shift"),
    ("hdr-img-noise", "linear", "standard_hdr_linear", 1, 0, "noise"),
    ("hdr-img-blur-paper", "linear", "paper_hdr_1000", 1, 0, "blur1"),
    ("hdr-vid-flicker2", "linear", "standard_hdr_linear", 12, 30, "flicker2"),
    ("hdr-vid-flicker4-paper", "linear", "paper_hdr_1000", 12, 60, "flicker4"),
    ("hdr-vid-ghost", "linear", "standard_hdr_linear", 12, 30, "ghost"),
    ("hdr-vid-shift-paper", "linear", "paper_hdr_1000", 10, 30, "shift"),
]
W, H = 192, 128
HDR_WHITE = 203.0  # cd/m2 of linear 1.0; highlights reach several times that


def gen(d):
    os.makedirs(d, exist_ok=True)
    manifest = []
    for i, (name, kind, disp, n, fps, how) in enumerate(CASES):
        rng = np.random.default_rng(100 + i)
        ref = video(W, H, n, seed=i) if n > 1 else [scene(W, H, seed=i)]
        test = distort(ref, how, rng)
        if kind == "srgb":
            r, t = np.stack([srgb(f) for f in ref]), np.stack([srgb(f) for f in test])
        else:
            boost = lambda f: np.clip(f, 0, None) * HDR_WHITE * (1 + 4 * (f > 0.8))
            r = np.stack([boost(f) for f in ref]).astype(np.float32)
            t = np.stack([boost(f) for f in test]).astype(np.float32)
        r.tofile(os.path.join(d, name + ".ref"))
        t.tofile(os.path.join(d, name + ".test"))
        manifest.append({"name": name, "kind": kind, "display": disp,
                         "display_spec": DISPLAYS[disp][0], "width": W, "height": H,
                         "frames": n, "fps": fps, "distortion": how})
    with open(os.path.join(d, "manifest.json"), "w") as f:
        json.dump(manifest, f, indent=1)
    print(f"{len(manifest)} cases in {d}")


def load(d, case, which):
    dtype = np.uint8 if case["kind"] == "srgb" else np.float32
    a = np.fromfile(os.path.join(d, case["name"] + "." + which), dtype=dtype)
    return a.reshape(case["frames"], case["height"], case["width"], 3)


def reference_case(d, cfg, case, device, key):
    import torch
    import pycvvdp
    from pycvvdp.cvvdp_metric import safe_pow

    metric = pycvvdp.cvvdp(display_name=case["display"], config_paths=[cfg], quiet=True,
                           device=device)
    r, t = load(d, case, "ref"), load(d, case, "test")
    t0 = time.perf_counter()
    if case["frames"] == 1:
        jod, stats = metric.predict(t[0], r[0], dim_order="HWC")
    else:
        jod, stats = metric.predict(t, r, dim_order="FHWC", frames_per_second=case["fps"])
    seconds = time.perf_counter() - t0
    res = {"jod": float(jod), "seconds": seconds, "ppd": float(metric.pix_per_deg)}
    q = torch.as_tensor(stats["Q_per_ch"], device=device)  # [batch, channel, frame, band]
    nch, nb = q.shape[1], q.shape[3]
    w = metric.get_ch_weights(nch)
    bw = torch.ones((1, nch, 1, nb), dtype=torch.float32, device=device)
    bw[:, :, 0, -1] = metric.baseband_weight[0:nch]
    q_sc = metric.lp_norm(q * w * bw, metric.beta_sch, dim=3, normalize=False)
    q_tc = metric.lp_norm(q_sc, metric.beta_tch, dim=1, normalize=False)
    if case["frames"] == 1:
        q_tc = q_tc * metric.image_int
    res["frame_jod"] = metric.met2jod(q_tc.flatten()).tolist()
    if nch == 4:
        tr = q_sc[:, 3:4]
        res["flicker_jod"] = float(metric.met2jod(
            metric.lp_norm(tr, metric.beta_t, dim=2, normalize=True).flatten())[0])
        p = metric.beta_tch
        res["transient_share"] = float(safe_pow(tr, p).sum() / safe_pow(q_sc, p).sum()) \
            if float(safe_pow(q_sc, p).sum()) > 0 else 0.0
    print(f"{key:<10} {case['name']:<26} {float(jod):.6f} JOD  {seconds:.2f} s", flush=True)
    return res


def ref(d):
    import torch
    import pycvvdp

    cfg = os.path.join(d, "config")
    os.makedirs(cfg, exist_ok=True)
    src = os.path.join(os.path.dirname(pycvvdp.__file__), "vvdp_data", "display_models.json")
    with open(src) as f:
        models = json.load(f)
    for key, (_, record) in DISPLAYS.items():
        if record is not None:
            models[key] = record
    with open(os.path.join(cfg, "display_models.json"), "w") as f:
        json.dump(models, f, indent=1)
    device = torch.device("cuda" if torch.cuda.is_available() else "cpu")
    with open(os.path.join(d, "manifest.json")) as f:
        manifest = json.load(f)
    out = {"device": str(device), "torch": torch.__version__,
           "gpu": torch.cuda.get_device_name(0) if device.type == "cuda" else None}
    # PyTorch lets cuDNN convolutions use TF32 on NVIDIA GPUs by default (10-bit mantissa). The
    # comparison uses full f32 ("cases"); "cases_tf32" keeps what the defaults give, for the record.
    for key, tf32 in (("cases", False), ("cases_tf32", True)):
        torch.backends.cudnn.allow_tf32 = tf32
        torch.backends.cuda.matmul.allow_tf32 = tf32
        out[key] = {}
        for case in manifest:
            out[key][case["name"]] = reference_case(d, cfg, case, device, key)
    with open(os.path.join(d, "reference.json"), "w") as f:
        json.dump(out, f, indent=1)


def compare(d):
    with open(os.path.join(d, "manifest.json")) as f:
        manifest = json.load(f)
    with open(os.path.join(d, "rust.json")) as f:
        rust = json.load(f)
    with open(os.path.join(d, "reference.json")) as f:
        refr = json.load(f)
    lines = [f"reference: cvvdp 0.5.7 on {refr['device']} ({refr.get('gpu')}), torch "
             f"{refr['torch']}; Rust: tessera-metrics cvvdp() over colorvideovdp 0.1.1",
             "",
             "| case | input | display | frames @ fps | reference JOD | Rust JOD | abs diff "
             "| per-frame max diff | flicker JOD ref / Rust | share ref / Rust | diff vs TF32 ref |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    worst = {"jod": 0.0, "frame": 0.0, "flicker": 0.0, "share": 0.0, "tf32": 0.0}
    for case in manifest:
        n = case["name"]
        a, b = refr["cases"][n], rust["cases"][n]
        dj = abs(a["jod"] - b["jod"])
        df = max(abs(x - y) for x, y in zip(a["frame_jod"], b["frame_jod"]))
        worst["jod"] = max(worst["jod"], dj)
        worst["frame"] = max(worst["frame"], df)
        fl = sh = "-"
        if a.get("flicker_jod") is not None:
            worst["flicker"] = max(worst["flicker"], abs(a["flicker_jod"] - b["flicker_jod"]))
            worst["share"] = max(worst["share"],
                                 abs(a["transient_share"] - b["transient_share"]))
            fl = f"{a['flicker_jod']:.4f} / {b['flicker_jod']:.4f}"
            sh = f"{a['transient_share']:.4f} / {b['transient_share']:.4f}"
        dt = abs(refr["cases_tf32"][n]["jod"] - b["jod"])
        worst["tf32"] = max(worst["tf32"], dt)
        fr = "image" if case["frames"] == 1 else f"{case['frames']} @ {case['fps']}"
        lines.append(f"| {n} | {case['kind']} | {case['display']} | {fr} | {a['jod']:.6f} "
                     f"| {b['jod']:.6f} | {dj:.2e} | {df:.2e} | {fl} | {sh} | {dt:.2e} |")
    lines.append("")
    lines.append(f"largest |JOD difference| {worst['jod']:.2e} (claim <= {TOL_JOD}); per-frame JOD "
                 f"{worst['frame']:.2e}; flicker JOD {worst['flicker']:.2e}; transient share "
                 f"{worst['share']:.2e}; against the reference with PyTorch's default TF32 "
                 f"convolutions {worst['tf32']:.2e}")
    text = "\n".join(lines)
    print(text)
    with open(os.path.join(d, "crosscheck-cvvdp-result.md"), "w") as f:
        f.write(text + "\n")
    return 0 if max(worst["jod"], worst["frame"], worst["flicker"]) <= TOL_JOD else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("step", choices=["gen", "ref", "compare", "all"])
    ap.add_argument("dir")
    ap.add_argument("--rust-bin", default="target/release/examples/cvvdp_crosscheck")
    args = ap.parse_args()
    if args.step in ("gen", "all"):
        gen(args.dir)
    if args.step == "all":
        subprocess.run([args.rust_bin, args.dir], check=True)
    if args.step in ("ref", "all"):
        ref(args.dir)
    if args.step in ("compare", "all"):
        sys.exit(compare(args.dir))


if __name__ == "__main__":
    main()
