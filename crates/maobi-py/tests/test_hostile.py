"""Hostile arguments (the Python half of the sweep in docs/testing.md, "Sweep of the Python API
and the controller paths"): each ends in a Python exception naming the argument, before any
memory is sized from it; never a panic, an abort, a hang or unbounded memory."""

import json
import os
import shutil
import struct

import numpy as np
import pytest

import maobi
from conftest import REPO

PAPER = REPO / "fixtures/robot/paper.json"
PEN1_GEN = REPO / "crates/neural-gen/data"


def test_files_that_never_end_or_block_are_refused_before_opening(tmp_path):
    # /dev/zero was read until memory ran out (an abort for calibrate, "out of memory" for the
    # others); a FIFO blocked the open forever.
    fifo = tmp_path / "m.csv"
    os.mkfifo(fifo)
    for path in ("/dev/zero", fifo):
        with pytest.raises(ValueError, match="measurements: .* not a regular file"):
            maobi.calibrate(path)
        with pytest.raises(ValueError, match="brush: .* not a regular file"):
            maobi.render_presses(np.zeros((0, 5)), 40.0, 32, brush=str(path))
        with pytest.raises(ValueError, match="font: .* not a regular file"):
            maobi.glyph("一", size_px=64, font=path)
        with pytest.raises(ValueError, match="path: .* not a regular file"):
            maobi.Track.load(path)
        with pytest.raises(ValueError, match="path: .* not a regular file"):
            maobi.load_image(path)
    with pytest.raises(ValueError, match="kinematics: /dev/zero is not a regular file"):
        maobi.robot.export(_track(), PAPER, format="aubo-lua", kinematics="/dev/zero")
    with pytest.raises(ValueError, match="path: .* is a folder"):
        maobi.Brush.load(tmp_path)


def test_a_generator_file_that_is_a_device_or_a_pipe_is_refused(tmp_path):
    shutil.copy(PEN1_GEN / "pen1.json", tmp_path / "g.json")
    os.symlink("/dev/zero", tmp_path / "g.safetensors")
    with pytest.raises(ValueError, match="path: .*g.safetensors is not a regular file"):
        maobi.Generator.load(tmp_path / "g.safetensors")
    os.remove(tmp_path / "g.json")
    os.mkfifo(tmp_path / "g.json")
    with pytest.raises(ValueError, match=r"path \(its config\): .*g.json is not a regular file"):
        maobi.Generator.load(tmp_path / "g.safetensors")


def test_hostile_generator_weights_are_refused(tmp_path):
    shutil.copy(PEN1_GEN / "pen1.json", tmp_path / "g.json")
    w = (PEN1_GEN / "pen1.safetensors").read_bytes()
    n = struct.unpack("<Q", w[:8])[0]
    header = json.loads(w[8 : 8 + n])
    name = next(k for k in header if k != "__metadata__")
    lying = dict(header)
    lying[name] = dict(header[name], shape=[2**20, 2**20])
    hb = json.dumps(lying).encode()
    cases = {
        "header length 2^62": struct.pack("<Q", 2**62) + b"{}",
        "cut at half": w[: len(w) // 2],
        "a shape of 2^40 values": struct.pack("<Q", len(hb)) + hb + w[8 + n :],
        "NaN weights": w[: 8 + n] + b"\xff" * (len(w) - 8 - n),
    }
    for what, data in cases.items():
        (tmp_path / "g.safetensors").write_bytes(data)
        with pytest.raises(maobi.MaobiError, match="g.safetensors"):
            maobi.Generator.load(tmp_path / "g.safetensors")
            pytest.fail(what)


def test_sizes_from_arguments_are_bounded_before_allocation():
    pen1 = maobi.Brush.builtin("pen1")
    # A broadcast of 10^10 presses (a view) was copied: 74.5 GiB asked of numpy.
    with pytest.raises(ValueError, match="broadcast to 10000000000 presses"):
        pen1.predict(np.full((100000, 1), 15.0), np.zeros((1, 100000)))
    # 10^5 presses of 128² px images (6.5 GB; 10^7 aborted the interpreter).
    g = maobi.Generator.load()
    with pytest.raises(ValueError, match="params: 100000 presses: expected at most 4096"):
        g.forward(np.tile([[15.0, 0.0, 0.0]], (100000, 1)))
    with pytest.raises(ValueError, match="params: 100000 presses"):
        g.vjp(np.tile([[15.0, 0.0, 0.0]], (100000, 1)), np.zeros((1, 1, 1)))
    # 300 characters at 4096 px: 60 GB of images, still running after a minute.
    with pytest.raises(ValueError, match="text: 300 characters at size_px=4096"):
        maobi.write("一" * 300, size_px=4096)
    with pytest.raises(ValueError, match="size_px=1000000"):
        maobi.render_presses(np.zeros((0, 5)), 40.0, 10**6)
    with pytest.raises(ValueError, match="image: 100000000×1 px"):
        maobi.save_image("never-written.png", np.zeros((1, 100_000_000), np.float32))
    assert not os.path.exists("never-written.png")

    def endless():
        while True:
            yield np.zeros((1, 5))

    # An endless iterable of strokes filled memory (4 GB at 44 s).
    with pytest.raises(ValueError, match="strokes: more than 100000 strokes"):
        maobi.Track(endless())


def test_coordinates_that_overflow_the_rasteriser_are_refused():
    # Both panicked ("attempt to subtract with overflow", a MaobiError "internal error").
    with pytest.raises(ValueError, match="box_mm: side 1e-300 mm at 64 px"):
        maobi.render_presses([[0, 0, 15.0, 0, 0]], 1e-300, 64, extrapolate=True)
    with pytest.raises(ValueError, match=r"presses\[0\]: \(x_mm, y_mm\) = \(1e300, -1e300\)"):
        maobi.render_presses([[1e300, -1e300, 15.0, 0, 0]], 40.0, 64, extrapolate=True)
    with pytest.raises(ValueError, match=r"box_mm: corner \(1e300, 0\)"):
        maobi.render_presses_soft([[10, 10, 15.0, 0, 0]], (1e300, 0, 40), 64)
    g = maobi.Generator.load()
    # Beyond f32: the gradient came back NaN.
    with pytest.raises(ValueError, match=r"grad_images\[0, 0, 0\]: 1e308"):
        g.vjp([[15.0, 0, 0]], np.full((1, g.size, g.size), 1e308))


def _track(**kw):
    return maobi.Track([np.array([[10, 10, 15.0, 0, 0], [20, 10, 15.0, 0, 0]])], box_mm=(0, 0, 40), **kw)


def test_a_track_from_json_is_validated_as_a_loaded_one(tmp_path):
    j = json.loads(_track().to_json())
    j["stroke_chars"] = [7]
    # Track.load refused it; Track.from_json accepted it, and robot.check planned no ink dip.
    for make in (lambda: maobi.Track.from_json(json.dumps(j)), lambda: maobi.Track.load(_write(tmp_path, j))):
        with pytest.raises(maobi.MaobiError, match="field `stroke_chars`: stroke 0 is given character 7"):
            make()
    for side in (0, -40, 1e308):
        j = json.loads(_track().to_json())
        j["char_box_mm"] = [0, 0, side]
        t = maobi.Track.from_json(json.dumps(j))
        # Rendered as an empty image before.
        with pytest.raises(ValueError, match="track: char_box_mm: side"):
            maobi.render_track(t, size_px=64)


def _write(tmp_path, j):
    p = tmp_path / "track.json"
    p.write_text(json.dumps(j), encoding="utf-8")
    return p


def test_odd_text_ends_in_a_value_error_naming_it():
    for text, msg in [
        ("", "text is empty"),
        ("\x00\x01", r"character '\\0' \(U\+0000\)"),
        ("一" * 10000, "text: 10000 characters"),
        ("\u202e", r"U\+202E"),
    ]:
        with pytest.raises(ValueError, match=msg):
            maobi.write(text, size_px=64)


def test_a_character_name_cannot_inject_into_a_program():
    evil = 'x")\nmovej([0,0,0,0,0,0])\n# ]]\nmove_joint({0,0,0,0,0,0})\n--[['
    t = maobi.Track(_yong().strokes, brush=_yong().brush, box_mm=_yong().box_mm, char=evil)
    for fmt, kw in [("urscript", {}), ("gcode", {}), ("aubo-lua", {"motion": "moves"})]:
        with pytest.warns(UserWarning) if fmt == "gcode" else _nothing():
            text = maobi.robot.export(t, PAPER, format=fmt, **kw)
        lines = text.splitlines()
        assert not any(line.startswith(("movej([0,0,0", "move_joint({0,0,0")) for line in lines), fmt


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *a):
        return False


_YONG = []


def _yong():
    if not _YONG:
        _YONG.append(maobi.write("一", size_px=64).track)
    return _YONG[0]
