#!/usr/bin/env python3
"""Captures the bytes the official AUBO SDK client (pyaubo-sdk, class RpcClient) sends for each
call maobi makes, for crates/robot-io/tests/wire_golden.rs.

    python3 -m pip install pyaubo-sdk==0.24.1     # CPython 3.11, x86-64 Linux wheel
    python3 crates/robot-io/tests/golden/capture_sdk.py > crates/robot-io/tests/golden/sdk_frames.json

The SDK holds the GIL while it waits for an answer, so the recording server runs in a second
process (this script with --serve). It listens on loopback only, records every frame it
receives and answers with canned results. Every wait is bounded.
"""
import json
import os
import socket
import subprocess
import sys
import tempfile
import time

CANNED = {
    "SystemInfo.getInterfaceVersionCode": 24000,
    "getRobotNames": ["rob1"],
    "getAxisNames": [],
    "rob1.MotionControl.getExecId": -1,
    "rob1.RobotState.isSteady": True,
    "rob1.RobotState.getTcpPose": [0.4, 0.1, 0.3, 3.141592653589793, 0.0, 0.0],
    "rob1.RobotState.getJointPositions": [0.0, 0.3, 1.6, 0.3, 1.57, 0.0],
}


def serve(port_file, log_path):
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(8)
    s.settimeout(60)
    with open(port_file, "w") as f:
        f.write(str(s.getsockname()[1]))
    log = open(log_path, "a")
    deadline = time.time() + 120
    while time.time() < deadline:
        try:
            c, _ = s.accept()
        except socket.timeout:
            return
        c.settimeout(30)
        buf = b""
        try:
            while True:
                d = c.recv(65536)
                if not d:
                    break
                buf += d
                while len(buf) >= 8:
                    assert buf[:3] == b"SOF" and buf[3] == 1, buf[:8]
                    n = int.from_bytes(buf[4:8], "big")
                    if len(buf) < 8 + n:
                        break
                    frame, buf = buf[: 8 + n], buf[8 + n :]
                    payload = frame[8:]
                    log.write(frame.hex() + "\n")
                    log.flush()
                    if payload.startswith(b"__login__"):
                        rep = b"__login__\nSUCCEED"
                    else:
                        r = json.loads(payload)
                        rep = json.dumps({"id": r["id"], "jsonrpc": "2.0", "result": CANNED.get(r["method"], 0)}).encode()
                    c.sendall(b"SOF\x01" + len(rep).to_bytes(4, "big") + rep)
        except (socket.timeout, ConnectionError):
            pass
        c.close()


def main():
    import pyaubo_sdk

    tmp = tempfile.mkdtemp()
    port_file, log_path = os.path.join(tmp, "port"), os.path.join(tmp, "frames.log")
    server = subprocess.Popen([sys.executable, __file__, "--serve", port_file, log_path])
    try:
        for _ in range(200):
            if os.path.exists(port_file) and open(port_file).read():
                break
            time.sleep(0.05)
        port = int(open(port_file).read())
        seen = 0

        def frames():
            nonlocal seen
            lines = open(log_path).read().split() if os.path.exists(log_path) else []
            new, seen = lines[seen:], len(lines)
            return new

        calls = []

        def record(name, args, fn):
            result = fn()
            calls.append({"call": name, "args": args, "result": result, "frames": frames()})

        c = pyaubo_sdk.RpcClient()
        c.setRequestTimeout(2000)
        record("connect", {}, lambda: c.connect("127.0.0.1", port))
        record("login", {"user": "aubo", "password": "123456"}, lambda: c.login("aubo", "123456"))
        record("getRobotNames", {}, c.getRobotNames)
        r = c.getRobotInterface("rob1")
        mc, rs = r.getMotionControl(), r.getRobotState()
        offset = [0.0, 0.0, 0.2, 0.0, 0.0, 0.0]
        record("setTcpOffset", {"offset": offset}, lambda: r.getRobotConfig().setTcpOffset(offset))
        record("setSpeedFraction", {"fraction": 0.5}, lambda: mc.setSpeedFraction(0.5))
        q = [0.0, 0.3, 1.6, 0.3, 1.57, 0.0]
        record("moveJoint", {"q": q, "a": 1.0, "v": 0.5}, lambda: mc.moveJoint(q, 1.0, 0.5, 0.0, 0.0))
        # Numbers that show how the SDK prints doubles (plain, 0.000d, d.de-XX, d.de+XX).
        for name, pose, a, v, blend in [
            ("moveLine", [0.4, -0.123456789012345, 1e-05, 3.141592653589793, 1e-07, -0.0], 0.3, 0.02, 0.0005),
            ("moveLine", [123456789012345.0, 1234567890123456.0, 1e16, 0.001, 0.0001, -2.5e-300], 2.0, 0.25, 0.002),
        ]:
            record(name, {"pose": pose, "a": a, "v": v, "blend_radius": blend},
                   lambda: mc.moveLine(pose, a, v, blend, 0.0))
        record("getExecId", {}, mc.getExecId)
        record("isSteady", {}, rs.isSteady)
        record("getTcpPose", {}, rs.getTcpPose)
        record("getJointPositions", {}, rs.getJointPositions)
        c.disconnect()
        frames()
        # The login digest for a range of passwords (and two users), one connection each.
        digests = []
        for user, pw in [("aubo", ""), ("aubo", "a"), ("aubo", "b"), ("aubo", "c"), ("aubo", "123456"),
                         ("aubo", "1234567"), ("other", "123456"), ("aubo", "A\x00\x7f ~"),
                         ("aubo", "ÿ中文"), ("aubo", "abcdefghijklmnopqrstuvwxyz")]:
            c = pyaubo_sdk.RpcClient()
            c.setRequestTimeout(2000)
            c.connect("127.0.0.1", port)
            frames()
            c.login(user, pw)
            login = [f for f in frames() if bytes.fromhex(f)[8:].startswith(b"__login__")]
            c.disconnect()
            payload = bytes.fromhex(login[0])[8:].decode()
            digests.append({"user": user, "password": pw, "frame": login[0], "digest": payload.split("\n")[2]})
        out = {
            "sdk": "pyaubo-sdk " + getattr(pyaubo_sdk, "__version__", "0.24.1"),
            "note": "frames are hex, as the SDK sent them; ids differ on every run",
            "calls": calls,
            "digests": digests,
        }
        print(json.dumps(out, indent=1, ensure_ascii=False))
    finally:
        server.terminate()
        server.wait(timeout=10)


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "--serve":
        serve(sys.argv[2], sys.argv[3])
    else:
        main()
