"""maobi.robot: the checked program, as `maobi robot check --json` and `robot export` build it."""

import json

import pytest

import maobi
from conftest import REPO, load_json

PAPER = REPO / "fixtures/robot/paper.json"


@pytest.fixture(scope="module")
def track_file(written_yong):
    return written_yong / "track.json"


def test_check_equals_the_cli(cli, track_file):
    want = json.loads(cli("robot", "check", track_file, "--paper", PAPER, "--json"))
    assert maobi.robot.check(track_file, PAPER) == want
    # A Track object and the paper as a dict: the same report.
    assert maobi.robot.check(maobi.Track.load(track_file), load_json(PAPER)) == want
    robot = REPO / "fixtures/robot/robot-ink.json"
    want_ink = json.loads(cli("robot", "check", track_file, "--paper", PAPER, "--robot", robot, "--json"))
    assert maobi.robot.check(track_file, PAPER, robot=robot) == want_ink


@pytest.mark.parametrize(
    "fmt, extra",
    [("urscript", []), ("gcode", []), ("aubo-lua", ["--motion", "moves"]), ("aubo-lua", ["--accept-nominal-kinematics"])],
)
def test_export_equals_the_cli(cli, tmp_path, track_file, fmt, extra):
    out = tmp_path / "program.txt"
    cli("robot", "export", track_file, "--paper", PAPER, "--format", fmt, *extra, "-o", out)
    kw = {}
    if "--motion" in extra:
        kw["motion"] = "moves"
    if "--accept-nominal-kinematics" in extra:
        kw["accept_nominal_kinematics"] = True
    assert maobi.robot.export(track_file, PAPER, format=fmt, **kw) == out.read_text(encoding="utf-8")


def test_an_unsafe_track_is_refused(track_file):
    t = maobi.Track.load(track_file)
    # Pressed 45 mm deep: beyond the brush's range, which the safety check refuses.
    deep = maobi.Track([s * [1, 1, 0, 1, 1] + [0, 0, 45, 0, 0] for s in t.strokes], brush=t.brush, box_mm=t.box_mm)
    with pytest.raises(maobi.MaobiError, match="fails the check"):
        maobi.robot.check(deep, PAPER)
    with pytest.raises(ValueError, match='format="svg"'):
        maobi.robot.export(t, PAPER, format="svg")
    with pytest.raises(ValueError, match="need the arm's own kinematics"):
        maobi.robot.export(t, PAPER, format="aubo-lua")
    with pytest.raises(ValueError, match="paper: .*touch_points: need at least 3"):
        maobi.robot.check(t, {"touch_points": []})
