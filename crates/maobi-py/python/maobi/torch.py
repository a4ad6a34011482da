"""maobi in PyTorch: the generator and the soft footprint renderer as autograd functions whose
backward pass is maobi's own vector–Jacobian product (no PyTorch graph through maobi).

- :func:`generator` — the B-BSMG generator, presses ``(B, 3)`` (``h_mm, alpha_rad,
  beta_rad``) to footprint images ``(B, S, S)``; backward through maobi's ``InputVjp``.
- :func:`render_presses` — presses ``(N, 5)`` (``x_mm, y_mm, h_mm, alpha_rad, beta_rad``) to
  the soft union image ``(size_px, size_px)`` of their footprints (the soft teardrop that
  ``maobi write --refine`` optimises); backward through its closed-form derivatives.

CPU tensors of any float dtype; the result has the input's dtype. A CUDA (or other device)
tensor raises ``ValueError``: there is no GPU path yet, move it with ``.cpu()``.

A FRIDA-style loop::

    import torch, maobi, maobi.torch
    target = torch.from_numpy(maobi.glyph("一", size_px=128))
    presses = torch.tensor([[20.0, 60.0, 15.0, 0.0, 0.0]] * 8, dtype=torch.float64, requires_grad=True)
    opt = torch.optim.Adam([presses], lr=0.5)
    for _ in range(50):
        opt.zero_grad()
        img = maobi.torch.render_presses(presses, box_mm=120.0, size_px=128, extrapolate=True)
        loss = ((img - target) ** 2).mean()
        loss.backward()
        opt.step()
"""

from __future__ import annotations

import operator
import threading
from typing import Any, Optional, Tuple, Union

try:
    import torch as _torch
except ImportError as e:  # pragma: no cover - exercised only without torch
    raise ImportError("maobi.torch needs PyTorch (pip install torch); the rest of maobi works without it") from e

from . import _native

BoxMm = Union[float, Tuple[float, float, float]]

_pen1_lock = threading.Lock()
_pen1: Optional[_native.Generator] = None


def _committed_generator() -> _native.Generator:
    global _pen1
    with _pen1_lock:
        if _pen1 is None:
            _pen1 = _native.Generator.load()
        return _pen1


def _cpu_float(t: Any, name: str) -> "_torch.Tensor":
    if not isinstance(t, _torch.Tensor):
        raise ValueError(f"{name}: expected a torch.Tensor, got {type(t).__name__}")
    if t.device.type != "cpu":
        raise ValueError(
            f"{name}: a tensor on {t.device}: maobi.torch runs on the CPU (no GPU path yet); move it with .cpu()"
        )
    if t.layout != _torch.strided:
        raise ValueError(f"{name}: a {t.layout} tensor (expected a dense one: .to_dense())")
    if not t.is_floating_point():
        raise ValueError(f"{name}: dtype {t.dtype} (expected a floating-point tensor)")
    return t


def _numpy(t: "_torch.Tensor"):
    return t.detach().to(_torch.float64).contiguous().numpy()


class _GeneratorFn(_torch.autograd.Function):
    @staticmethod
    def forward(ctx, params, gen, extrapolate):  # type: ignore[override]
        images = gen.forward(_numpy(params), extrapolate=extrapolate)
        ctx.gen = gen
        ctx.extrapolate = extrapolate
        ctx.save_for_backward(params)
        return _torch.from_numpy(images).to(params.dtype)

    @staticmethod
    def backward(ctx, grad_images):  # type: ignore[override]
        (params,) = ctx.saved_tensors
        g = ctx.gen.vjp(_numpy(params), _numpy(grad_images), extrapolate=ctx.extrapolate)
        return _torch.from_numpy(g).to(params.dtype), None, None


def generator(
    params: "_torch.Tensor", *, gen: Optional[_native.Generator] = None, extrapolate: bool = False
) -> "_torch.Tensor":
    """Footprint images of the B-BSMG generator for ``params`` ``(B, 3)`` (``h_mm, alpha_rad,
    beta_rad``): ``(B, S, S)``, ink = 1, in ``params``' dtype. Differentiable with respect to
    ``params``; the backward pass is maobi's ``InputVjp`` (``Generator.vjp``). ``gen``: a
    :class:`maobi.Generator` (default: the committed pen1 generator). Raises ``ValueError`` for
    a press outside the ranges the generator was trained on unless ``extrapolate=True``."""
    params = _cpu_float(params, "params")
    if params.dim() != 2 or params.shape[1] != 3:
        raise ValueError(f"params: shape {tuple(params.shape)} (expected (B, 3): h_mm, alpha_rad, beta_rad)")
    if gen is not None and not isinstance(gen, _native.Generator):
        raise TypeError(f"gen: expected a maobi.Generator, got {type(gen).__name__}")
    return _GeneratorFn.apply(params, gen if gen is not None else _committed_generator(), extrapolate)


class _RenderFn(_torch.autograd.Function):
    @staticmethod
    def forward(ctx, presses, box_mm, size_px, brush, edge_px, extrapolate):  # type: ignore[override]
        img = _native.render_presses_soft(
            _numpy(presses), box_mm, size_px, brush=brush, edge_px=edge_px, extrapolate=extrapolate
        )
        ctx.args = (box_mm, size_px, brush, edge_px, extrapolate)
        ctx.save_for_backward(presses)
        return _torch.from_numpy(img).to(presses.dtype)

    @staticmethod
    def backward(ctx, grad_image):  # type: ignore[override]
        (presses,) = ctx.saved_tensors
        box_mm, size_px, brush, edge_px, extrapolate = ctx.args
        _, g = _native.render_presses_soft_vjp(
            _numpy(presses), box_mm, size_px, _numpy(grad_image), brush=brush, edge_px=edge_px, extrapolate=extrapolate
        )
        return _torch.from_numpy(g).to(presses.dtype), None, None, None, None, None


def render_presses(
    presses: "_torch.Tensor",
    box_mm: BoxMm,
    size_px: int,
    *,
    brush: Union[str, _native.Brush, None] = None,
    edge_px: float = 0.75,
    extrapolate: bool = False,
) -> "_torch.Tensor":
    """The soft union image ``(size_px, size_px)`` of the presses' soft footprints (ink = 1,
    in ``presses``' dtype), as :func:`maobi.render_presses_soft`: each row of ``presses``
    ``(N, 5)`` (``x_mm, y_mm, h_mm, alpha_rad, beta_rad``) a footprint whose root end sits at
    ``(x_mm, y_mm)`` pointing along ``beta_rad``, edges softened over ``edge_px`` pixels.
    ``box_mm``: the paper square shown (a side in mm, or ``(x0_mm, y0_mm, side_mm)``).
    Differentiable with respect to ``presses``; the backward pass is maobi's closed-form
    soft-footprint VJP. Raises ``ValueError`` for a press outside the brush's calibrated ranges
    unless ``extrapolate=True`` (an optimiser may step outside: clamp, or extrapolate)."""
    presses = _cpu_float(presses, "presses")
    if presses.dim() != 2 or presses.shape[1] != 5:
        raise ValueError(
            f"presses: shape {tuple(presses.shape)} (expected (N, 5): x_mm, y_mm, h_mm, alpha_rad, beta_rad)"
        )
    # An integer, as maobi.render_presses_soft takes it (64.9 is refused, not cut to 64).
    size_px = operator.index(size_px)
    return _RenderFn.apply(presses, box_mm, size_px, brush, float(edge_px), bool(extrapolate))


__all__ = ["generator", "render_presses"]
