"""maobi from Python: a calibrated brush model, a differentiable footprint renderer, the
character pipeline and checked robot programs, with numpy arrays in and out.

Units: lengths in millimetres and angles in radians, the unit in every argument's name
(``h_mm``, ``alpha_rad``); images are ``float32`` arrays of shape ``(H, W)`` with ink = 1.
Presses are rows ``x_mm, y_mm, h_mm, alpha_rad, beta_rad``: the footprint's root end on the
paper (x right, y down), the press depth, the brush tilt and the footprint's direction (root to
tip, from +x towards +y).

Errors are ``ValueError`` (an argument out of its domain, named in the message),
``FileNotFoundError`` and :class:`MaobiError` for what maobi refuses. PyTorch is optional:
``maobi.torch`` needs it, ``import maobi`` does not.

>>> import maobi
>>> w = maobi.write("永")
>>> w.executed.shape
(512, 512)
"""

from . import robot
from ._native import (
    Brush,
    Generator,
    MaobiError,
    Track,
    Written,
    __version__,
    calibrate,
    compare,
    csim,
    glyph,
    iou,
    load_image,
    render_presses,
    render_presses_soft,
    render_presses_soft_vjp,
    render_track,
    save_image,
    ssim,
    write,
)

__all__ = [
    "Brush",
    "Generator",
    "MaobiError",
    "Track",
    "Written",
    "__version__",
    "calibrate",
    "compare",
    "csim",
    "glyph",
    "iou",
    "load_image",
    "render_presses",
    "render_presses_soft",
    "render_presses_soft_vjp",
    "render_track",
    "robot",
    "save_image",
    "ssim",
    "write",
]
