"""The LearningToPaint-sized network in PyTorch (CPU): the reference for benches/ltp.rs.

    python3 crates/neural-gen/benches/ltp_torch.py [--threads 2] [--steps 20] [--json]

Same layers, batch, loss and optimiser as neural_gen::ltp: FC 3→512→1024→2048→4096, six 3×3
convolutions with a ×2 pixel shuffle after every second, sigmoid, MSE, Adam at batch 64.
Prints the mean seconds per training step (forward, backward, Adam split out) and inference
images per second at batch 1 and 64, after warm-up.
"""
import argparse
import json
import time

import torch
import torch.nn as nn
import torch.nn.functional as F


class Ltp(nn.Module):
    def __init__(self):
        super().__init__()
        self.fcs = nn.ModuleList(nn.Linear(a, b) for a, b in [(3, 512), (512, 1024), (1024, 2048), (2048, 4096)])
        self.convs = nn.ModuleList(nn.Conv2d(a, b, 3, 1, 1) for a, b in [(16, 32), (32, 32), (8, 16), (16, 16), (4, 8), (8, 4)])
        self.shuffle = nn.PixelShuffle(2)

    def forward(self, x):
        for fc in self.fcs:
            x = F.relu(fc(x))
        x = x.view(-1, 16, 16, 16)
        for i, conv in enumerate(self.convs):
            x = conv(x)
            x = self.shuffle(x) if i % 2 == 1 else F.relu(x)
        return torch.sigmoid(x)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    torch.manual_seed(0)
    net = Ltp()
    opt = torch.optim.Adam(net.parameters(), lr=1e-4)
    x = torch.rand(64, 3)
    target = torch.rand(64, 1, 128, 128)
    fwd = bwd = adam = 0.0
    for i in range(a.steps + 3):
        t0 = time.perf_counter()
        loss = F.mse_loss(net(x), target)
        t1 = time.perf_counter()
        opt.zero_grad()
        loss.backward()
        t2 = time.perf_counter()
        opt.step()
        t3 = time.perf_counter()
        if i >= 3:
            fwd += t1 - t0
            bwd += t2 - t1
            adam += t3 - t2
    n = a.steps
    res = {"torch": torch.__version__, "threads": a.threads, "params": sum(p.numel() for p in net.parameters()),
           "step_s": (fwd + bwd + adam) / n, "forward_s": fwd / n, "backward_s": bwd / n, "adam_s": adam / n}
    with torch.no_grad():
        for b in (1, 64):
            xb = torch.rand(b, 3)
            for _ in range(3):
                net(xb)
            reps = max(5, 640 // b)
            t0 = time.perf_counter()
            for _ in range(reps):
                net(xb)
            res[f"inference_b{b}_img_per_s"] = b * reps / (time.perf_counter() - t0)
    if a.json:
        print(json.dumps(res))
    else:
        print(f"PyTorch {res['torch']}, {a.threads} threads, {res['params']} parameters")
        print(f"step {res['step_s']:.3f} s = forward {res['forward_s']:.3f} + backward {res['backward_s']:.3f}"
              f" + Adam {res['adam_s']:.3f}")
        print(f"inference: {res['inference_b1_img_per_s']:.0f} img/s at batch 1, "
              f"{res['inference_b64_img_per_s']:.0f} img/s at batch 64")


if __name__ == "__main__":
    main()
