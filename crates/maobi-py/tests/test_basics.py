"""The package imports without torch, says its version, and its errors are Python exceptions."""

import re
import subprocess
import sys

import numpy as np
import pytest

import maobi
from conftest import REPO


def test_version_is_the_workspace_version():
    text = (REPO / "Cargo.toml").read_text(encoding="utf-8")
    want = re.search(r'^version = "([^"]+)"', text, re.M).group(1)
    assert maobi.__version__ == want


def test_import_does_not_need_torch():
    # A fresh interpreter where `import torch` fails: maobi still imports and renders.
    code = (
        "import sys; sys.modules['torch'] = None\n"
        "import maobi\n"
        "img = maobi.render_presses([[5, 5, 15, 0, 0]], 30.0, 32)\n"
        "print(maobi.__version__, img.dtype, img.shape)\n"
        "try:\n"
        "    import maobi.torch\n"
        "except ImportError as e:\n"
        "    print('no torch:', e)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "float32 (32, 32)" in r.stdout
    assert "no torch: maobi.torch needs PyTorch" in r.stdout


def test_maobi_error_is_an_exception_and_a_panic_becomes_one():
    assert issubclass(maobi.MaobiError, Exception)
    with pytest.raises(maobi.MaobiError, match="internal error in maobi.*deliberate panic"):
        maobi._native._panic_for_tests()


@pytest.mark.parametrize(
    "call, exc, message",
    [
        (lambda: maobi.Brush.builtin("pen9"), ValueError, "pen9.*expected one of pen1, pen2"),
        (lambda: maobi.render_presses(np.zeros((3, 4)), 30.0, 32), ValueError, r"presses: shape \[3, 4\].*\(N, 5\)"),
        (lambda: maobi.render_presses([[1, 2, np.nan, 0, 0]], 30.0, 32), ValueError, r"presses\[0, 2\]: NaN"),
        (lambda: maobi.render_presses(np.zeros((2, 5), complex), 30.0, 32), ValueError, "presses: dtype complex128"),
        (lambda: maobi.render_presses([["a"] * 5], 30.0, 32), ValueError, "presses: dtype <U1"),
        (lambda: maobi.render_presses([[5, 5, 30, 0, 0]], 30.0, 32), ValueError, r"presses\[0\]: h_mm = 30.*extrapolate=True"),
        (lambda: maobi.render_presses([[5, 5, 15, 0, 0]], -1.0, 32), ValueError, "box_mm: side -1"),
        (lambda: maobi.render_presses([[5, 5, 15, 0, 0]], 30.0, 0), ValueError, "size_px=0"),
        (lambda: maobi.render_presses([[5, 5, 15, 0, 0]], 30.0, 32, brush="nope"), ValueError, "not a built-in brush"),
        (lambda: maobi.render_presses([[5, 5, 15, 0, 0]], 30.0, 32, model="spline"), ValueError, "model=\"spline\""),
        (lambda: maobi.csim(np.zeros((8, 8)), np.zeros((8, 9))), ValueError, "a is 8×8 px, b is 9×8 px"),
        (lambda: maobi.csim(np.zeros(8), np.zeros(8)), ValueError, r"a: shape \[8\].*\(H, W\)"),
        (lambda: maobi.write("A"), ValueError, "give font=.*hanzi_data="),
        (lambda: maobi.write(""), ValueError, "text is empty"),
        (lambda: maobi.write("永", alpha_rad=1.0), ValueError, "alpha_rad=1.*tilt range"),
        (lambda: maobi.write("永", size_px=10), ValueError, "size_px=10"),
        (lambda: maobi.write("永", font="/nonexistent/font.ttf"), FileNotFoundError, "font: /nonexistent/font.ttf"),
        (lambda: maobi.Brush.load("/nonexistent/brush.json"), FileNotFoundError, "nonexistent/brush.json"),
        (lambda: maobi.Track.load("/nonexistent/track.json"), FileNotFoundError, "nonexistent/track.json"),
        (lambda: maobi.Brush.from_json("{}"), maobi.MaobiError, "not a valid brush profile"),
        (lambda: maobi.glyph("永和"), ValueError, "exactly one character"),
        (lambda: maobi.Brush.builtin("pen1").predict([11, 30]), ValueError, r"press\[1\]: h_mm = 30"),
        (lambda: maobi.Brush.builtin("pen1").predict([1, 2], [0, 0, 0]), ValueError, "do not broadcast"),
    ],
)
def test_bad_inputs_raise_named_errors(call, exc, message):
    with pytest.raises(exc, match=message):
        call()


def test_any_float_dtype_and_layout_is_accepted():
    # Values exact in float32 too.
    rows = np.array([[5, 10, 15, 0.0625, 0.03125], [12, 10, 12, 0.0, 0.0]])
    want = maobi.render_presses(rows, 30.0, 48)
    assert want.dtype == np.float32 and want.shape == (48, 48) and want.flags.c_contiguous
    # float32, a Fortran-ordered copy, a strided view and a plain list give the same pixels.
    assert np.array_equal(maobi.render_presses(rows.astype(np.float32), 30.0, 48), want)
    assert np.array_equal(maobi.render_presses(np.asfortranarray(rows), 30.0, 48), want)
    wide = np.zeros((2, 10))
    wide[:, ::2] = rows
    assert np.array_equal(maobi.render_presses(wide[:, ::2], 30.0, 48), want)
    assert np.array_equal(maobi.render_presses(rows.tolist(), 30.0, 48), want)
    assert np.array_equal(maobi.render_presses(rows.astype(np.int64), 30.0, 48), maobi.render_presses(rows.astype(np.int64).astype(float), 30.0, 48))
    img32 = want.astype(np.float32)
    assert maobi.csim(img32, want.astype(np.float16)) > 0.999
    assert maobi.csim(img32.T.copy().T, img32) == pytest.approx(1.0)
