"""What calling maobi from Python costs, and maobi.torch.generator against PyTorch.

    python crates/maobi-py/benches/python_overhead.py [--rounds 5] [--threads 2] [--json]

For each call (render 1,000 presses at 512²; csim of two 512² images; the generator's forward
and VJP at batch 64) it times the call from Python (wall time, `time.perf_counter`) and the
library work inside it as Rust measures it (`maobi._native._last_call_seconds()`: the time
with the GIL released, around the library call alone), interleaved call by call; the
difference is the cost of the Python boundary (argument checks and conversions, the result
array). Then `maobi.torch.generator` forward + backward at batch 64 against the same network
in PyTorch (the committed pen1 weights, PyTorch's autograd), interleaved round by round, both
at `--threads` (rayon's RAYON_NUM_THREADS and torch.set_num_threads). Medians of `--rounds`
rounds of 10 calls each. docs/python.md gives the figures and the command.
"""

import argparse
import json
import os
import statistics
import sys
import time

ap = argparse.ArgumentParser()
ap.add_argument("--rounds", type=int, default=5)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--json", action="store_true")
a = ap.parse_args()
os.environ["RAYON_NUM_THREADS"] = str(a.threads)

import numpy as np  # noqa: E402

import maobi  # noqa: E402
from maobi import _native  # noqa: E402

rng = np.random.default_rng(0)
n = 1000
presses = np.column_stack(
    [rng.uniform(5, 95, n), rng.uniform(5, 95, n), rng.uniform(11, 20, n), rng.uniform(0, 0.17, n), rng.uniform(0, 0.08, n)]
)
img_a = maobi.render_presses(presses[:500], 100.0, 512)
img_b = maobi.render_presses(presses[500:], 100.0, 512)
gen = maobi.Generator.load()
params = np.column_stack([rng.uniform(11, 20, 64), rng.uniform(0, 0.17, 64), rng.uniform(0, 0.08, 64)])
up = rng.uniform(-1, 1, (64, 128, 128)).astype(np.float32)

calls = {
    "render 1,000 presses, 512²": lambda: maobi.render_presses(presses, 100.0, 512),
    "csim of two 512² images": lambda: maobi.csim(img_a, img_b),
    "generator forward, batch 64": lambda: gen.forward(params),
    "generator VJP, batch 64": lambda: gen.vjp(params, up),
}
rows = {k: ([], []) for k in calls}
for _ in range(a.rounds):
    for name, f in calls.items():
        wall, inner = [], []
        f()
        for _ in range(10):
            t0 = time.perf_counter()
            f()
            wall.append(time.perf_counter() - t0)
            inner.append(_native._last_call_seconds())
        rows[name][0].append(statistics.median(wall))
        rows[name][1].append(statistics.median(inner))

out = {"threads": a.threads, "rounds": a.rounds, "calls": {}}
for name, (wall, inner) in rows.items():
    w, i = statistics.median(wall), statistics.median(inner)
    out["calls"][name] = {"python_ms": 1e3 * w, "rust_ms": 1e3 * i, "overhead_ms": 1e3 * (w - i)}

try:
    import torch

    import maobi.torch

    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
    from test_torch import torch_generator

    torch.set_num_threads(a.threads)
    net = torch_generator()
    p64 = torch.from_numpy(params)
    w64 = torch.from_numpy(up.astype(np.float64))

    def ours():
        x = p64.clone().requires_grad_(True)
        (maobi.torch.generator(x, gen=gen) * w64).sum().backward()

    def theirs():
        x = p64.clone().requires_grad_(True)
        (net(x).double() * w64).sum().backward()

    pair = {"maobi.torch.generator": ([], ours), "PyTorch (same network)": ([], theirs)}
    for f in (ours, theirs):
        f()
    for _ in range(a.rounds):
        for name, (times, f) in pair.items():
            ts = []
            for _ in range(5):
                t0 = time.perf_counter()
                f()
                ts.append(time.perf_counter() - t0)
            times.append(statistics.median(ts))
    out["torch"] = {
        "version": torch.__version__,
        "forward_backward_batch_64_ms": {k: 1e3 * statistics.median(v[0]) for k, v in pair.items()},
    }
except ImportError as e:
    out["torch"] = f"skipped: {e}"

if a.json:
    print(json.dumps(out, indent=2))
else:
    print(f"threads {a.threads}, medians of {a.rounds} rounds")
    for name, r in out["calls"].items():
        print(f"{name:32s} Python {r['python_ms']:8.2f} ms  Rust {r['rust_ms']:8.2f} ms  overhead {r['overhead_ms']:6.2f} ms")
    if isinstance(out["torch"], dict):
        for k, v in out["torch"]["forward_backward_batch_64_ms"].items():
            print(f"{k:32s} forward + backward, batch 64: {v:8.2f} ms")
    else:
        print("torch:", out["torch"])
