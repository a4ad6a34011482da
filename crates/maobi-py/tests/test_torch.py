"""maobi.torch: autograd functions whose backward is maobi's VJP, checked by gradcheck and
finite differences, and a PyTorch optimisation through them that lowers an image loss."""

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="PyTorch is not installed: the maobi.torch tests are skipped")

import maobi  # noqa: E402
import maobi.torch  # noqa: E402
from conftest import REPO  # noqa: E402


def test_render_presses_passes_gradcheck():
    torch.manual_seed(0)
    presses = torch.tensor(
        [[8.0, 12.0, 14.0, 0.05, 0.3], [14.0, 13.0, 17.0, 0.1, 2.5]], dtype=torch.float64, requires_grad=True
    )
    # A small canvas (24² px at 1 mm) keeps the numerical Jacobian quick; a wide soft edge keeps
    # the finite differences smooth. Tolerance: 1e-4 absolute and relative, float64 throughout.
    f = lambda p: maobi.torch.render_presses(p, 24.0, 24, edge_px=2.0, extrapolate=True)  # noqa: E731
    assert torch.autograd.gradcheck(f, (presses,), eps=1e-6, atol=1e-4, rtol=1e-4)


def test_render_presses_forward_is_the_soft_render():
    p = torch.tensor([[10.0, 20.0, 15.0, 0.0, 0.02]], dtype=torch.float32)
    img = maobi.torch.render_presses(p, 40.0, 64)
    assert img.dtype == torch.float32 and img.shape == (64, 64)
    want = maobi.render_presses_soft(p.double().numpy(), 40.0, 64)
    assert np.allclose(img.numpy(), want, atol=1e-6)


def torch_generator():
    """The pen1 generator in PyTorch with the committed weights (read from the safetensors file
    with numpy): the architecture of crates/neural-gen/benches/gen_vjp_torch.py, inputs
    normalised onto [-1, 1] over the config's ranges."""
    import torch.nn.functional as F

    data = REPO / "crates/neural-gen/data"
    cfg = json.loads((data / "pen1.json").read_text())
    raw = (data / "pen1.safetensors").read_bytes()
    n = int.from_bytes(raw[:8], "little")
    header = json.loads(raw[8 : 8 + n])
    body = raw[8 + n :]
    w = {}
    for name, meta in header.items():
        if name == "__metadata__":
            continue
        assert meta["dtype"] == "F32", meta
        a, b = meta["data_offsets"]
        w[name] = torch.from_numpy(np.frombuffer(body[a:b], dtype="<f4").reshape(meta["shape"]).copy())
    arch = cfg["arch"]
    ranges = cfg.get("ranges", cfg["profile"]["ranges"])
    lo = torch.tensor([ranges[k]["min"] for k in ("h_mm", "alpha_rad", "beta_rad")], dtype=torch.float64)
    hi = torch.tensor([ranges[k]["max"] for k in ("h_mm", "alpha_rad", "beta_rad")], dtype=torch.float64)
    fcs = len(arch["hidden"]) + 1

    def net(p):
        x = (2 * (p - lo) / (hi - lo) - 1).float()
        for i in range(fcs):
            x = F.linear(x, w[f"fc{i}.weight"], w[f"fc{i}.bias"])
            if i + 1 < fcs:
                x = F.relu(x)
        x = x.view(-1, arch["seed_channels"], arch["seed_side"], arch["seed_side"])
        for i in range(len(arch["stages"])):
            x = F.conv2d(x, w[f"conv{i}.weight"], w[f"conv{i}.bias"], padding=1)
            if i + 1 < len(arch["stages"]):
                x = F.relu(x)
            x = F.pixel_shuffle(x, 2)
        return torch.sigmoid(x)[:, 0]

    return net


def test_generator_equals_pytorch_autograd_of_the_same_network():
    net = torch_generator()
    params = torch.tensor([[14.0, 0.05, 0.03], [17.0, 0.1, 0.06], [19.5, 0.16, 0.01]], dtype=torch.float64)
    w = torch.rand(3, 128, 128, dtype=torch.float64, generator=torch.Generator().manual_seed(3)) - 0.5
    ours = params.clone().requires_grad_(True)
    img = maobi.torch.generator(ours)
    (img * w).sum().backward()
    ref = params.clone().requires_grad_(True)
    img_ref = net(ref)
    (img_ref.double() * w).sum().backward()
    # The same network in float32 on other kernels: images to 1e-5, gradients to 1e-3 relative.
    assert torch.allclose(img, img_ref.double(), atol=1e-5)
    assert torch.allclose(ours.grad, ref.grad, rtol=1e-3, atol=1e-3 * ref.grad.abs().max().item()), (ours.grad, ref.grad)


def test_an_optimisation_through_render_presses_lowers_an_image_loss():
    # Target: a horizontal bar drawn by eight presses; start: the same presses 3 mm too high,
    # too light and turned. Adam on the presses through maobi's VJP pulls them onto it.
    size, box = 96, 60.0
    xs = np.linspace(12, 40, 8)
    target_p = np.stack([xs, np.full(8, 30.0), np.full(8, 16.0), np.zeros(8), np.zeros(8)], 1)
    target = torch.from_numpy(maobi.render_presses(target_p, box, size)).double()
    start = target_p + np.array([0.0, -3.0, -3.0, 0.0, 0.3])
    presses = torch.tensor(start, requires_grad=True)
    opt = torch.optim.Adam([presses], lr=0.3)
    losses = []
    for _ in range(40):
        opt.zero_grad()
        img = maobi.torch.render_presses(presses, box, size, extrapolate=True)
        loss = ((img - target) ** 2).mean()
        loss.backward()
        opt.step()
        losses.append(loss.item())
    assert losses[-1] < 0.25 * losses[0], losses
    assert abs(presses[:, 1].mean().item() - 30.0) < 1.0, presses


def test_an_optimisation_through_the_generator_lowers_an_image_loss():
    gen = maobi.Generator.load()
    target = torch.from_numpy(gen.forward([[18.0, 0.1, 0.05]])).double()
    params = torch.tensor([[13.0, 0.03, 0.02]], dtype=torch.float64, requires_grad=True)
    opt = torch.optim.Adam([params], lr=0.2)
    losses = []
    for _ in range(30):
        opt.zero_grad()
        loss = ((maobi.torch.generator(params, gen=gen, extrapolate=True) - target) ** 2).mean()
        loss.backward()
        opt.step()
        losses.append(loss.item())
    assert losses[-1] < 0.2 * losses[0], losses


def test_tensors_off_the_cpu_are_refused():
    meta = torch.zeros(2, 5, device="meta")
    with pytest.raises(ValueError, match="maobi.torch runs on the CPU.*cpu\\(\\)"):
        maobi.torch.render_presses(meta, 40.0, 32)
    with pytest.raises(ValueError, match=r"params: shape \(2, 5\)"):
        maobi.torch.generator(torch.zeros(2, 5))
    with pytest.raises(ValueError, match="floating-point"):
        maobi.torch.render_presses(torch.zeros(2, 5, dtype=torch.int64), 40.0, 32)


def test_hostile_tensors_are_refused_naming_the_argument():
    p = torch.zeros((2, 5)).to_sparse()
    # A sparse tensor raised torch's RuntimeError ("unsupported memory format").
    with pytest.raises(ValueError, match="presses: a torch.sparse_coo tensor"):
        maobi.torch.render_presses(p, 40.0, 64)
    # A string as the generator raised AttributeError inside forward.
    with pytest.raises(TypeError, match="gen: expected a maobi.Generator, got str"):
        maobi.torch.generator(torch.ones((1, 3)), gen="pen1")
    # 64.9 px was cut to 64 silently.
    with pytest.raises(TypeError):
        maobi.torch.render_presses(torch.zeros((1, 5)), 40.0, 64.9)
    with pytest.raises(ValueError, match="params: 5000000 presses"):
        maobi.torch.generator(torch.tensor([[15.0, 0, 0]]).repeat(5_000_000, 1))
