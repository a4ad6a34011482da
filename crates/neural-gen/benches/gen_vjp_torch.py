"""The B-BSMG generator in PyTorch (CPU): the reference for benches/gen_vjp.rs.

    python3 crates/neural-gen/benches/gen_vjp_torch.py [--config crates/neural-gen/data/pen1.json]
        [--threads 2] [--batch 64] [--reps 20] [--json]

Builds the architecture of the config JSON beside the committed weights (FC 3→hidden…→seed map,
ReLU between; per stage a 3×3 convolution, padding 1, ReLU except after the last, then a ×2
pixel shuffle; sigmoid) with random weights (timing only), and times what track refinement
needs: a forward pass of a batch of presses and the vector–Jacobian product with respect to
the inputs (torch.autograd.grad of Σ upstream·image, weights frozen so no weight gradients are
computed). Prints the mean seconds per batch after warm-up, the forward alone (no_grad), and
one training step of the network alone (forward, MSE against a fixed target batch, backward,
Adam with weight decay 0: what benches/generator.rs's `generator_training/network_step_batch_64`
times).
"""
import argparse
import json
import os
import time

import torch
import torch.nn as nn
import torch.nn.functional as F


class Gen(nn.Module):
    def __init__(self, arch):
        super().__init__()
        widths = [3] + list(arch["hidden"]) + [arch["seed_channels"] * arch["seed_side"] ** 2]
        self.fcs = nn.ModuleList(nn.Linear(a, b) for a, b in zip(widths[:-1], widths[1:]))
        self.convs = nn.ModuleList(nn.Conv2d(a, b, 3, 1, 1) for a, b in arch["stages"])
        self.c, self.s = arch["seed_channels"], arch["seed_side"]

    def forward(self, x):
        for i, fc in enumerate(self.fcs):
            x = fc(x)
            if i + 1 < len(self.fcs):
                x = F.relu(x)
        x = x.view(-1, self.c, self.s, self.s)
        for i, conv in enumerate(self.convs):
            x = conv(x)
            if i + 1 < len(self.convs):
                x = F.relu(x)
            x = F.pixel_shuffle(x, 2)
        return torch.sigmoid(x)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default=os.path.join(here, "../data/pen1.json"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    torch.manual_seed(0)
    with open(a.config) as f:
        cfg = json.load(f)
    net = Gen(cfg["arch"])
    for p in net.parameters():
        p.requires_grad_(False)
    size = cfg["size"]
    x0 = torch.rand(a.batch, 3) * 2 - 1
    up = torch.rand(a.batch, 1, size, size) - 0.5

    def vjp():
        x = x0.clone().requires_grad_(True)
        y = net(x)
        (g,) = torch.autograd.grad((y * up).sum(), x)
        return y, g

    for _ in range(3):
        vjp()
    t0 = time.perf_counter()
    for _ in range(a.reps):
        vjp()
    t_vjp = (time.perf_counter() - t0) / a.reps
    with torch.no_grad():
        for _ in range(3):
            net(x0)
        t0 = time.perf_counter()
        for _ in range(a.reps):
            net(x0)
        t_fwd = (time.perf_counter() - t0) / a.reps
    for p in net.parameters():
        p.requires_grad_(True)
    opt = torch.optim.Adam(net.parameters(), lr=1e-4)
    target = torch.rand(a.batch, 1, size, size)

    def step():
        opt.zero_grad(set_to_none=True)
        loss = F.mse_loss(net(x0), target)
        loss.backward()
        opt.step()

    for _ in range(3):
        step()
    t0 = time.perf_counter()
    for _ in range(a.reps):
        step()
    t_step = (time.perf_counter() - t0) / a.reps
    out = {
        "torch": torch.__version__,
        "threads": a.threads,
        "batch": a.batch,
        "forward_vjp_s": t_vjp,
        "forward_s": t_fwd,
        "train_step_s": t_step,
    }
    if a.json:
        print(json.dumps(out))
    else:
        print(f"PyTorch {torch.__version__}, {a.threads} threads, batch {a.batch}:")
        print(f"  forward + input VJP: {t_vjp * 1e3:.1f} ms per batch ({t_vjp / a.batch * 1e3:.2f} ms per image)")
        print(f"  forward alone:       {t_fwd * 1e3:.1f} ms per batch")
        print(f"  training step:       {t_step * 1e3:.1f} ms per batch (Adam, MSE)")


if __name__ == "__main__":
    main()
