"""Rendering presses and tracks, and the metrics, against the CLI (`stroke`, `write`'s
render.png, `compare --json`)."""

import json

import numpy as np
import pytest

import maobi
from conftest import load_json

# One 8-bit grey level: PNG files hold what the float images hold to half of it.
LEVEL = 1.0 / 255.0


@pytest.mark.parametrize("h, a_deg, b_deg", [(15.0, 0.0, 0.0), (19.0, 8.0, 4.0)])
def test_one_press_equals_maobi_stroke(cli, tmp_path, h, a_deg, b_deg):
    png = tmp_path / "stroke.png"
    meta = json.loads(cli("stroke", "--h", h, "--alpha", a_deg, "--beta", b_deg, "--size", 128, "-o", png, "--json"))
    k = meta["px_per_mm"]
    ax, ay = (v / k for v in meta["anchor_px"])
    press = [[ax, ay, h, np.deg2rad(a_deg), np.deg2rad(b_deg)]]
    img = maobi.render_presses(press, 128 / k, 128)
    want = maobi.load_image(png)
    assert img.shape == want.shape == (128, 128)
    assert np.abs(img - want).max() <= LEVEL
    assert img.sum() > 100, "the footprint is drawn"


def test_presses_compose_by_maximum_and_lifted_ones_leave_nothing():
    a = [[10, 20, 15, 0, 0]]
    b = [[14, 21, 18, 0, 0.5]]
    both = maobi.render_presses(a + b + [[30, 30, 0, 0, 0]], 40.0, 96)
    assert np.array_equal(both, np.maximum(maobi.render_presses(a, 40.0, 96), maobi.render_presses(b, 40.0, 96)))
    assert maobi.render_presses([[30, 30, -1, 0, 0]], 40.0, 96).max() == 0.0


def test_box_corner_shifts_the_image():
    p = [[25, 25, 15, 0, 0]]
    shifted = maobi.render_presses([[15, 5, 15, 0, 0]], (-10.0, -20.0, 40.0), 80)
    assert np.array_equal(maobi.render_presses(p, 40.0, 80), shifted)


def test_the_soft_render_is_close_to_the_analytic_one():
    p = [[10, 20, 15, 0, 0.02], [18, 22, 17, 0.05, 0.8]]
    hard = maobi.render_presses(p, 40.0, 128)
    soft = maobi.render_presses_soft(p, 40.0, 128, edge_px=0.75)
    assert soft.dtype == np.float64 and soft.shape == (128, 128)
    # The same teardrops: only the edges differ.
    assert maobi.iou(hard, soft.astype(np.float32)) > 0.97
    assert np.abs(hard - soft).mean() < 0.01


def test_render_track_is_the_plan_and_render_png(written_yong):
    w = maobi.write("永", size_px=128)
    assert np.array_equal(maobi.render_track(w.track, size_px=128), w.plan)
    cli_track = maobi.Track.load(written_yong / "track.json")
    plan = maobi.render_track(cli_track, size_px=128)
    assert np.abs(plan - maobi.load_image(written_yong / "render.png")).max() <= LEVEL
    assert np.array_equal(plan, w.plan)


def test_metrics_equal_maobi_compare(cli, written_yong):
    a, b = written_yong / "reference.png", written_yong / "executed.png"
    want = json.loads(cli("compare", a, b, "--json"))
    assert maobi.compare(a, b) == want
    ia, ib = maobi.load_image(a), maobi.load_image(b)
    assert maobi.compare(ia, ib) == want
    assert (maobi.csim(ia, ib), maobi.ssim(ia, ib), maobi.iou(ia, ib)) == (want["csim"], want["ssim"], want["iou"])
    same = maobi.compare(ia, ia)
    assert same["csim"] == pytest.approx(1.0) and same["psnr"] is None


def test_the_report_figures_are_the_metrics_of_the_images():
    w = maobi.write("永", size_px=128)
    r = w.report
    assert r["plan"]["csim"] == maobi.csim(w.reference, w.plan)
    assert r["executed"]["ssim"] == maobi.ssim(w.reference, w.executed)
    assert r["agreement"]["iou"] == maobi.iou(w.plan, w.executed)


def test_save_image_writes_what_load_image_reads(tmp_path):
    img = maobi.render_presses([[10, 20, 15, 0, 0]], 40.0, 64)
    p = tmp_path / "x.png"
    maobi.save_image(p, img)
    assert np.abs(maobi.load_image(p) - img).max() <= LEVEL
    with pytest.raises(ValueError, match="coverage in"):
        maobi.save_image(p, img * 2)
