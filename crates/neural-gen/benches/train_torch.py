"""The Python peer of `maobi train`: a PyTorch training loop whose targets OpenCV renders.

    python3 crates/neural-gen/benches/train_torch.py [--config crates/neural-gen/data/pen1.json]
        [--threads 2] [--batch 64] [--steps 10] [--json]

What a user without maobi would write: per step, `--batch` presses drawn uniformly over the
config's calibrated ranges, each target footprint (a teardrop of two mirrored cubic Béziers from
the root to the tip, rotated by β, 128² in [0, 1]) filled by OpenCV (`cv2.fillPoly`,
anti-aliased, 4 bits of sub-pixel precision) in one thread, then the generator of
`gen_vjp_torch.py` (same architecture) does forward, MSE, backward and Adam (weight decay 0).
The footprint's length and width follow the press roughly (timing only: the geometry is not the
B-BSM's, the amount of drawing is). Prints the mean seconds per step after warm-up, and the
share of it spent rendering; the figure `benches/generator.rs`'s
`generator_training/train_job_10_steps_batch_64` (the whole `neural_gen::train` job, its own
renderer, 10 steps) is compared with, per step.
"""
import argparse
import json
import math
import os
import time

import cv2
import numpy as np
import torch
import torch.nn.functional as F

from gen_vjp_torch import Gen


def cubic(p0, p1, p2, p3, n=24):
    t = np.linspace(0.0, 1.0, n)[:, None]
    return ((1 - t) ** 3) * p0 + 3 * ((1 - t) ** 2) * t * p1 + 3 * (1 - t) * t * t * p2 + (t ** 3) * p3


def render(press, ranges, size, px_per_mm):
    """One footprint, 128² float32 in [0, 1] (ink = 1), centred as `maobi stroke` centres it."""
    (h0, h1), (a0, a1), _ = ranges
    h, a, beta = press
    fh = (h - h0) / max(h1 - h0, 1e-9)
    length = (6.0 + 14.0 * fh) * (1.0 + 0.2 * (a - a0) / max(a1 - a0, 1e-9))
    width = 1.5 + 3.5 * fh
    up = cubic(np.array([0.0, 0.0]), np.array([0.0, 0.9 * width]), np.array([0.55 * length, 1.1 * width]),
               np.array([length, 0.0]))
    lo = up[::-1] * np.array([1.0, -1.0])
    pts = np.concatenate([up, lo[1:]]) - np.array([0.5 * length, 0.0])
    c, s = math.cos(beta), math.sin(beta)
    pts = pts @ np.array([[c, s], [-s, c]])
    pts = (pts * px_per_mm + size / 2.0) * 16.0
    img = np.zeros((size, size), np.uint8)
    cv2.fillPoly(img, [pts.astype(np.int32)], 255, cv2.LINE_AA, 4)
    return img.astype(np.float32) / 255.0


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default=os.path.join(here, "../data/pen1.json"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    cv2.setNumThreads(1)
    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    with open(a.config) as f:
        cfg = json.load(f)
    size = cfg["size"]
    r = cfg["ranges"]
    ranges = [(r[k]["min"], r[k]["max"]) for k in ("h_mm", "alpha_rad", "beta_rad")]
    px_per_mm = float(cfg.get("px_per_mm", 8.0))
    net = Gen(cfg["arch"])
    opt = torch.optim.Adam(net.parameters(), lr=2e-3)
    render_s = total_s = 0.0
    for i in range(a.steps + 3):
        t0 = time.perf_counter()
        u = rng.random((a.batch, 3))
        presses = [tuple(r0 + (r1 - r0) * v for (r0, r1), v in zip(ranges, row)) for row in u]
        target = torch.from_numpy(np.stack([render(p, ranges, size, px_per_mm) for p in presses]))
        target = target.view(a.batch, 1, size, size)
        x = torch.from_numpy((u * 2 - 1).astype(np.float32))
        t1 = time.perf_counter()
        opt.zero_grad(set_to_none=True)
        loss = F.mse_loss(net(x), target)
        loss.backward()
        opt.step()
        t2 = time.perf_counter()
        if i >= 3:
            render_s += t1 - t0
            total_s += t2 - t0
    out = {
        "torch": torch.__version__,
        "opencv": cv2.__version__,
        "threads": a.threads,
        "batch": a.batch,
        "step_s": total_s / a.steps,
        "render_s": render_s / a.steps,
    }
    if a.json:
        print(json.dumps(out))
    else:
        print(f"PyTorch {torch.__version__} + OpenCV {cv2.__version__}, {a.threads} threads, batch {a.batch}:")
        print(f"  training step: {out['step_s'] * 1e3:.1f} ms (rendering the targets {out['render_s'] * 1e3:.1f} ms)")


if __name__ == "__main__":
    main()
