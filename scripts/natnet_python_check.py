#!/usr/bin/env python3
"""Interop check: packets encoded by emoshift's NatNet stand-in must be accepted, strictly,
by python_natnet's deserialize (an independent NatNet 3 implementation, BSD-3, kept in
../shared only). CI runs it from scripts/interop-natnet.

    pip install attrs
    PYTHONPATH=../shared/data/natnet/python_natnet python3 scripts/natnet_python_check.py

Builds and runs `cargo run -p protocol --example natnet_packets` (own target dir), then checks
each packet's decoded fields against what the example wrote. Exit status 0 on success.
"""

import os
import struct
import subprocess
import sys
import tempfile

from natnet.protocol import (MocapFrameMessage, ModelDefinitionsMessage, ServerInfoMessage,
                             EchoResponseMessage, Version, deserialize)
from natnet.protocol.ModelDefinitionsMessage import MarkersetDescription, RigidBodyDescription


def packets(path):
    data = open(path, "rb").read()
    off, out = 0, []
    while off < len(data):
        (n,) = struct.unpack_from("<H", data, off)
        out.append(data[off + 2 : off + 2 + n])
        off += 2 + n
    return out


def close(a, b, tol=1e-6):
    return all(abs(x - y) <= tol for x, y in zip(a, b))


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "packets.bin")
        env = dict(os.environ, CARGO_TARGET_DIR=os.environ.get("CARGO_TARGET_DIR", os.path.join(root, "target")))
        subprocess.run(["cargo", "run", "-q", "-p", "protocol", "--example", "natnet_packets", "--", out],
                       cwd=root, env=env, check=True)
        pk = packets(out)
    v3 = Version(3)
    info, defs, echo, *frames = [deserialize(p, version=v3, strict=True) for p in pk]
    assert isinstance(info, ServerInfoMessage), info
    assert info.app_name == "emoshift-stand-in" and info.natnet_version == Version(3)
    assert info.high_resolution_clock_frequency == 10_000_000
    assert info.connection_info.data_port == 1511 and info.connection_info.multicast
    assert info.connection_info.multicast_address == "239.255.42.99"
    assert isinstance(defs, ModelDefinitionsMessage)
    ms = [m for m in defs.models if isinstance(m, MarkersetDescription)]
    rb = [m for m in defs.models if isinstance(m, RigidBodyDescription)]
    assert [(m.name, m.marker_names) for m in ms] == [("face", ["M1", "M2", "M3"]),
                                                      ("all", ["face_1", "face_2", "face_3"])]
    assert rb[0].name == "head" and rb[0].id_ == 7 and rb[0].parent_id == -1
    assert len(rb[0].marker_positions) == 3 and rb[0].required_active_labels == [0, 0, 0]
    assert isinstance(echo, EchoResponseMessage)
    assert (echo.request_timestamp, echo.received_timestamp) == (42, 123_456_789)
    assert len(frames) == 5
    for i, f in enumerate(frames):
        n = 1000 + i
        assert isinstance(f, MocapFrameMessage) and f.frame_number == n
        assert [m.name for m in f.markersets] == ["face", "all"]
        t = i * 0.001
        for j, p in enumerate(f.markersets[0].markers):
            assert close(p, (0.1 * j + t, 1.5, -0.2)), p
        assert [(b.id_, b.tracking_valid) for b in f.rigid_bodies] == [(7, True)]
        assert close(f.rigid_bodies[0].orientation, (0, 0, 0, 1))
        assert [s.id_ for s in f.skeletons] == [3] and f.skeletons[0].rigid_bodies[0].id_ == 3 << 16 | 1
        lm = f.labelled_markers
        assert [(m.model_id, m.marker_id) for m in lm] == [(7, 1), (7, 2), (7, 3)]
        assert all(m.point_cloud_solved and m.has_model and not m.occluded for m in lm)
        assert abs(f.timing_info.timestamp - n / 120.0) < 1e-12
        ti = f.timing_info
        assert (ti.camera_mid_exposure_timestamp, ti.camera_data_received_timestamp, ti.transmit_timestamp) == (1000, 2000, 3000)
        assert f.tracked_models_changed == (n == 1004)
    print(f"python_natnet accepted all {len(pk)} packets emoshift encoded")
    return 0


if __name__ == "__main__":
    sys.exit(main())
