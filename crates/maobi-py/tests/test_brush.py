"""Brushes and calibration against `maobi footprint --json` and `maobi calibrate --json`."""

import json

import numpy as np
import pytest

import maobi
from conftest import REPO, load_json


def test_builtin_brushes_and_their_ranges():
    pen1 = maobi.Brush.builtin("pen1")
    assert pen1.name == "pen1" and pen1.source == "nominal"
    assert (pen1.length_mm, pen1.radius_mm) == (48.0, 6.0)
    assert pen1.ranges["h_mm"] == (11.0, 20.0)
    assert "pen1-s25" in maobi.Brush.builtins()


@pytest.mark.parametrize("h, a_deg, b_deg", [(11.0, 0.0, 0.0), (15.5, 4.0, 2.5), (20.0, 10.0, 5.0), (13.25, 7.5, 0.0)])
def test_predict_equals_the_cli_footprint(cli, h, a_deg, b_deg):
    want = json.loads(cli("footprint", "--h", h, "--alpha", a_deg, "--beta", b_deg, "--json"))
    lt, lh, lr = maobi.Brush.builtin("pen1").predict(h, np.deg2rad(a_deg), np.deg2rad(b_deg))
    assert (float(lt), float(lh), float(lr)) == (want["lt_mm"], want["lh_mm"], want["lr_mm"])


def test_predict_extrapolates_only_when_asked(cli):
    pen1 = maobi.Brush.builtin("pen1")
    with pytest.raises(ValueError, match=r"h_mm = 25.*calibrated range \[11"):
        pen1.predict(25.0)
    want = json.loads(cli("footprint", "--h", 25, "--alpha", 0, "--extrapolate", "--json"))
    lt, _, _ = pen1.predict(25.0, extrapolate=True)
    assert float(lt) == want["lt_mm"]
    with pytest.raises(ValueError, match="h_mm = 60: expected a depth from 0 to the brush's length 48"):
        pen1.predict(60.0, extrapolate=True)


def test_predict_broadcasts_like_numpy():
    pen1 = maobi.Brush.builtin("pen1")
    h = np.linspace(11, 20, 4).reshape(4, 1)
    a = np.array([0.0, 0.05, 0.1])
    lt, lh, lr = pen1.predict(h, a)
    assert lt.shape == lh.shape == lr.shape == (4, 3)
    for i in range(4):
        for j in range(3):
            one = pen1.predict(float(h[i, 0]), float(a[j]))
            assert (lt[i, j], lh[i, j], lr[i, j]) == tuple(float(v) for v in one)
    # Deeper presses make longer and wider footprints (the nominal model's signs).
    assert np.all(np.diff(lt[:, 0]) > 0) and np.all(np.diff(lr[:, 0]) > 0)


def test_save_and_load_round_trip(tmp_path):
    pen2 = maobi.Brush.builtin("pen2")
    p = tmp_path / "pen2.json"
    pen2.save(p)
    back = maobi.Brush.load(p)
    assert back == pen2 and back.to_json() == pen2.to_json()
    assert maobi.Brush.from_json(pen2.to_json()) == pen2
    assert not list(tmp_path.glob("*.tmp")), "the temporary file is renamed away"


def test_calibrate_equals_the_cli(cli, tmp_path):
    csv = REPO / "fixtures/measurements/pen1-sample.csv"
    out = tmp_path / "cal.json"
    report_cli = json.loads(cli("calibrate", csv, "--json", "-o", out))
    brush, report = maobi.calibrate(csv, name="cal")
    assert report == report_cli
    assert json.loads(brush.to_json()) == load_json(out)
    # The same rows as an (N, 6) array in radians: the same fit.
    rows = np.genfromtxt(csv, delimiter=",", names=True)
    arr = np.stack(
        [rows["h_mm"], np.deg2rad(rows["alpha_deg"]), np.deg2rad(rows["beta_deg"]), rows["lt_mm"], rows["lh_mm"], rows["lr_mm"]],
        axis=1,
    )
    brush2, report2 = maobi.calibrate(arr, name="cal")
    for k in ("lt_mm", "lh_mm", "lr_mm"):
        assert np.allclose(list(report2["outputs"][k]["coef"].values()), list(report["outputs"][k]["coef"].values()), rtol=1e-9)
    assert brush2.source == "calibrated"
    with pytest.raises(ValueError, match=r"measurements\[0, 3\] \(lt_mm\) = -1"):
        maobi.calibrate([[12, 0, 0, -1, 3, 2]])
