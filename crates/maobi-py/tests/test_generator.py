"""The generator's forward pass and its VJP (against finite differences of the forward pass)."""

import numpy as np
import pytest

import maobi


@pytest.fixture(scope="module")
def gen():
    return maobi.Generator.load()


def test_forward_images(gen):
    assert gen.size == 128 and gen.brush.name == "pen1"
    params = np.array([[12.0, 0.02, 0.01], [19.0, 0.15, 0.08]])
    imgs = gen.forward(params)
    assert imgs.dtype == np.float32 and imgs.shape == (2, 128, 128)
    assert 0.0 <= imgs.min() and imgs.max() <= 1.0
    # A deeper, more tilted press leaves more ink.
    assert imgs[1].sum() > imgs[0].sum() > 50
    # Batched or one by one: the same images.
    assert np.array_equal(gen.forward(params[1:]), imgs[1:])


def test_vjp_against_finite_differences(gen):
    rng = np.random.default_rng(7)
    params = np.array([[14.0, 0.05, 0.03], [17.5, 0.12, 0.06]])
    up = rng.uniform(-1, 1, (2, 128, 128))
    g = gen.vjp(params, up)
    assert g.shape == (2, 3) and g.dtype == np.float64
    # Central differences of Σ up·forward. The network is piecewise linear (ReLU) in float32:
    # steps of 0.01 mm and 0.001 rad agree with the exact VJP to 10 % of the press's largest
    # partial (measured: 3.6 % and 6.7 %); the exact check is against PyTorch's autograd of the
    # same network in test_torch.py.
    steps = [0.01, 0.001, 0.001]
    for i in range(2):
        for k in range(3):
            p, m = params.copy(), params.copy()
            p[i, k] += steps[k]
            m[i, k] -= steps[k]
            fd = ((gen.forward(p)[i].astype(np.float64) - gen.forward(m)[i]) * up[i]).sum() / (2 * steps[k])
            assert abs(g[i, k] - fd) <= 0.1 * np.abs(g[i]).max(), (i, k, g[i, k], fd)
    # Linear in the upstream gradient.
    assert np.allclose(gen.vjp(params, 2 * up), 2 * g, rtol=1e-5, atol=1e-6)


def test_bad_generator_inputs(gen):
    with pytest.raises(ValueError, match=r"params\[0\]: h_mm = 30.*trained on"):
        gen.forward([[30.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match=r"grad_images: shape \[1, 64, 64\]"):
        gen.vjp([[15.0, 0.0, 0.0]], np.zeros((1, 64, 64)))
    with pytest.raises(FileNotFoundError):
        maobi.Generator.load("/nonexistent/gen.safetensors")
