"""`maobi.write` against `maobi write`: the same report, track and images."""

import json

import numpy as np
import pytest

import maobi
from conftest import REPO, load_json, without_timing

LEVEL = 1.0 / 255.0


def test_one_character_equals_the_cli(written_yong):
    w = maobi.write("永", size_px=128)
    assert isinstance(w, maobi.Written) and w.char == "永"
    assert without_timing(w.report) == without_timing(load_json(written_yong / "report.json"))
    assert json.loads(w.track.to_json()) == load_json(written_yong / "track.json")
    for img, name in [(w.reference, "reference"), (w.plan, "render"), (w.executed, "executed")]:
        assert img.dtype == np.float32 and img.shape == (128, 128)
        assert np.abs(img - maobi.load_image(written_yong / f"{name}.png")).max() <= LEVEL, name
    assert np.array_equal(maobi.glyph("永", size_px=128), w.reference)


def test_the_free_width_plan_is_asked_for_as_in_the_cli(cli, written_yong, tmp_path):
    # Off by default, in both.
    assert load_json(written_yong / "report.json")["plan"]["free_widths"] is None
    out = tmp_path / "free"
    cli("write", "十", "--size", "96", "--free-widths", "-o", out)
    w = maobi.write("十", size_px=96, free_widths=True)
    free = w.report["plan"]["free_widths"]
    assert set(free) == {"csim", "ssim", "iou"} and 0.5 < free["csim"] <= 1.0
    assert without_timing(w.report) == without_timing(load_json(out / "report.json"))
    # The free widths change nothing else in the report.
    plain = maobi.write("十", size_px=96).report
    assert plain["plan"]["free_widths"] is None
    assert without_timing({**plain, "plan": {**plain["plan"], "free_widths": free}}) == without_timing(w.report)


def test_several_characters_share_one_box_and_equal_the_cli(cli, tmp_path):
    out = tmp_path / "two"
    cli("write", "永和", "--size", "96", "-o", out)
    ws = maobi.write("永 和", size_px=96)
    assert [w.char for w in ws] == ["永", "和"]
    assert ws[0].report["char_mm"] == ws[1].report["char_mm"]
    for i, w in enumerate(ws):
        d = out / f"{i + 1:02}-{w.char}"
        assert without_timing(w.report) == without_timing(load_json(d / "report.json"))
        assert json.loads(w.track.to_json()) == load_json(d / "track.json")


def test_refine_equals_the_cli(cli, tmp_path):
    out = tmp_path / "refined"
    cli("write", "十", "--size", "96", "--refine", "--iters", "3", "-o", out)
    w = maobi.write("十", size_px=96, refine=True, iters=3)
    assert w.report["refine"]["options"]["iterations"] == 3
    assert without_timing(w.report) == without_timing(load_json(out / "report.json"))


def test_a_font_glyph_equals_the_cli(cli, tmp_path):
    font = REPO / "fixtures/fonts/ukai-subset.ttf"
    out = tmp_path / "font"
    cli("write", "永", "--font", font, "--size", "96", "-o", out)
    w = maobi.write("永", size_px=96, font=font)
    assert without_timing(w.report) == without_timing(load_json(out / "report.json"))
    assert np.array_equal(maobi.glyph("永", size_px=96, font=font), w.reference)


def test_a_track_round_trips_and_is_built_from_arrays(tmp_path):
    w = maobi.write("十", size_px=64)
    p = tmp_path / "track.json"
    w.track.save(p)
    back = maobi.Track.load(p)
    assert back.to_json() == w.track.to_json()
    assert back.char == "十" and back.box_mm == w.track.box_mm and len(back) == len(w.track)
    strokes = back.strokes
    assert all(s.shape[1] == 5 and s.dtype == np.float64 for s in strokes)
    rebuilt = maobi.Track(strokes, brush=back.brush, char="十", box_mm=back.box_mm)
    assert rebuilt.to_json() == back.to_json()
    assert np.array_equal(maobi.render_track(rebuilt, size_px=64), w.plan)
    # A track moved 1 mm right renders 1 mm right.
    moved = maobi.Track([s + [1, 0, 0, 0, 0] for s in strokes], box_mm=back.box_mm)
    assert not np.array_equal(maobi.render_track(moved, size_px=64), w.plan)
