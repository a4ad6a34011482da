"""Golden values for stroke-metrics, computed independently with scikit-image and numpy.

Needs: numpy, scikit-image (pip install numpy scikit-image).
Run from this folder:  python3 gen_metrics.py > metrics.json
Images are stored as 8-bit hex (value/255 as float32 is the ink level, ink = 1), so Rust and
Python see bit-identical inputs. `tests/golden.rs` recomputes every figure.
"""
import json

import numpy as np
from skimage.draw import ellipse, polygon
from skimage.filters import gaussian
from skimage.metrics import structural_similarity

rng = np.random.default_rng(1123)


def q(img):
    return np.clip(np.round(img * 255), 0, 255).astype(np.uint8)


def blob(h, w, cy, cx, ry, rx, rot):
    img = np.zeros((h, w))
    rr, cc = ellipse(cy, cx, ry, rx, shape=img.shape, rotation=rot)
    img[rr, cc] = 1.0
    return gaussian(img, sigma=0.8)


def teardrop(h, w, shift):
    img = np.zeros((h, w))
    t = np.linspace(0, np.pi, 40)
    xs = 20 + shift + 70 * (1 - np.cos(t)) / 2
    ys = 64 + 22 * np.sin(t) * (1 - t / np.pi * 0.7)
    rr, cc = polygon(np.r_[ys, 128 - ys[::-1]], np.r_[xs, xs[::-1]], shape=img.shape)
    img[rr, cc] = 1.0
    return gaussian(img, sigma=0.7)


pairs = {
    "noise_32x32": (q(rng.random((32, 32))), q(rng.random((32, 32)))),
    "blobs_48x64": (q(blob(48, 64, 24, 30, 12, 20, 0.3)), q(blob(48, 64, 26, 33, 11, 18, 0.5))),
    "noisy_copy_40x40": None,
    "teardrops_128": (q(teardrop(128, 128, 0)), q(teardrop(128, 128, 3))),
    "const_20x24": (np.full((20, 24), 51, np.uint8), np.full((20, 24), 204, np.uint8)),
}
base = q(blob(40, 40, 20, 20, 12, 9, 1.0))
noisy = np.clip(base.astype(int) + rng.integers(-20, 21, base.shape), 0, 255).astype(np.uint8)
pairs["noisy_copy_40x40"] = (base, noisy)

out = {}
for name, (a8, b8) in pairs.items():
    a = (a8.astype(np.float32) / np.float32(255)).astype(np.float64)
    b = (b8.astype(np.float32) / np.float32(255)).astype(np.float64)
    ssim = structural_similarity(a, b, data_range=1.0, gaussian_weights=True, sigma=1.5,
                                 use_sample_covariance=False)
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    csim = float(a.ravel() @ b.ravel() / (na * nb)) if na > 0 and nb > 0 else (1.0 if na == nb == 0 else 0.0)
    ma, mb = a >= 0.5, b >= 0.5
    union = np.logical_or(ma, mb).sum()
    iou = float(np.logical_and(ma, mb).sum() / union) if union else 1.0
    mse = float(np.mean((a - b) ** 2))
    out[name] = {
        "width": int(a8.shape[1]),
        "height": int(a8.shape[0]),
        "a_hex": a8.tobytes().hex(),
        "b_hex": b8.tobytes().hex(),
        "ssim": float(ssim),
        "csim": csim,
        "iou": iou,
        "mse": mse,
    }
print(json.dumps(out, indent=1))
