"""Robot programs of a track, checked as ``maobi robot check`` checks them.

``paper`` is a ``paper.json`` path or its content as a dict (touched points: paper mm to robot
metres); ``robot`` a ``robot.json`` path or dict (speeds, heights, limits; the defaults when
``None``). Both functions build the same checked program as the CLI: every move through the
safety envelope, refused with :class:`maobi.MaobiError` when the track cannot be written safely.
"""

from __future__ import annotations

import os
from typing import Any, Dict, Literal, Optional, Union

from . import _native

PathLike = Union[str, "os.PathLike[str]"]


def check(
    track: Union["_native.Track", PathLike],
    paper: Union[PathLike, Dict[str, Any]],
    robot: Union[PathLike, Dict[str, Any], None] = None,
) -> Dict[str, Any]:
    """The safety report of the track's program, as ``maobi robot check --json`` prints it.

    Keys: ``strokes``, ``points``, ``moves``, ``dips``, ``max_press_mm`` (deepest press, mm),
    ``frame_residual_mm`` (paper fit, mm), ``estimated_seconds`` (s), ... and ``timing`` (each
    pressed stroke timed on the nominal AUBO-i5: durations in s, speeds in m/s, joint speeds in
    rad/s). Raises :class:`maobi.MaobiError` when the program fails the check.
    """
    return _native.robot_check(track, paper, robot)


def export(
    track: Union["_native.Track", PathLike],
    paper: Union[PathLike, Dict[str, Any]],
    format: Literal["urscript", "gcode", "aubo-lua"] = "urscript",
    robot: Union[PathLike, Dict[str, Any], None] = None,
    *,
    kinematics: Optional[PathLike] = None,
    motion: Literal["path-buffer", "moves"] = "path-buffer",
    accept_nominal_kinematics: bool = False,
) -> str:
    """The program text, as ``maobi robot export --format FORMAT`` writes it.

    ``format``: ``"urscript"`` (UR ``movep`` process moves), ``"gcode"`` (timed feeds, mm and
    mm/min) or ``"aubo-lua"`` (ARCS Lua). ``"aubo-lua"`` writes path buffers of joint waypoints,
    which need the arm's own kinematic parameters (``kinematics``: the file of ``maobi robot
    kinematics``) or ``accept_nominal_kinematics=True``; ``motion="moves"`` writes compacted,
    blended moves instead. G-code's warnings (as the CLI prints them) are ``UserWarning``\\ s.
    """
    return _native.robot_export(
        track,
        paper,
        format,
        robot,
        kinematics=kinematics,
        motion=motion,
        accept_nominal_kinematics=accept_nominal_kinematics,
    )


__all__ = ["check", "export"]
