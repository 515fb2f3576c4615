#!/usr/bin/env python3
"""The NatNet interop checks of scripts/interop-natnet (run by it, inside a network namespace
whose only interface is loopback). python_natnet (../shared/data/natnet/python_natnet, BSD-3,
an independent NatNet 3 implementation) is the peer; it is used from ../shared, never copied.

A. python_natnet's encoder streams a 109-marker synthetic face (one markerset, "Face", with its
   model definitions and 29.97 drop-frame timecode) into `emoshift serve` over multicast on
   loopback; the same take goes in over OSC beside it. Both streams must come out edited
   identically, frame for frame, none lost, each with the timecode it went in with. The model
   is trained on the take with its markers named as Motive exports them ("Face:<marker>"), so
   the live stream matches it with no mapping.
B. The real Motive 2.1 capture (raw/traffic.pcapng) is served again over unicast to
   `emoshift record`, stopped with Ctrl-C; the CSV it leaves must hold every frame
   NaturalPoint's SampleClient printed, at its printed precision (2 decimals, metres).

Prints PASS/FAIL per check and "N passed, M failed"; exit status 1 on any failure.
"""

import os
import re
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ["NATNET_SHARED"]
EMOSHIFT = os.environ["EMOSHIFT"]
sys.path.insert(0, os.path.join(SHARED, "python_natnet"))
sys.path.insert(0, os.path.join(ROOT, "scripts"))

from natnet.protocol import (EchoResponseMessage, MocapFrameMessage,  # noqa: E402
                             ModelDefinitionsMessage, ServerInfoMessage, Version, deserialize,
                             serialize)
from natnet.protocol.MocapFrameMessage import Markerset, TimingInfo  # noqa: E402
from natnet.protocol.ModelDefinitionsMessage import MarkersetDescription  # noqa: E402
from natnet.protocol.ServerInfoMessage import ConnectionInfo  # noqa: E402
from natnet_fixtures import parse_sampleclient, pcapng_packets, udp_payload  # noqa: E402

GROUP = "239.255.42.99"
results = []


def check(name, ok, detail=""):
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else ": " + str(detail)), flush=True)
    results.append(bool(ok))


def free_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


# ---- OSC, by hand (OSC 1.0: big-endian, 4-byte aligned) ----

def osc_str(s):
    b = s.encode() + b"\0"
    return b + b"\0" * (-len(b) % 4)


def osc_msg(addr, tags, payload):
    return osc_str(addr) + osc_str("," + tags) + payload


def osc_bundle(*msgs):
    return b"#bundle\0" + struct.pack(">II", 0, 1) + b"".join(
        struct.pack(">I", len(m)) + m for m in msgs)


def osc_messages(data):
    """(address, tags, argument bytes) of every message, bundles flattened."""
    if data.startswith(b"#bundle\0"):
        out, off = [], 16
        while off < len(data):
            (n,) = struct.unpack_from(">I", data, off)
            out += osc_messages(data[off + 4: off + 4 + n])
            off += 4 + n
        return out
    a_end = data.index(b"\0")
    addr = data[:a_end].decode()
    t_at = (a_end + 4) & ~3
    t_end = data.index(b"\0", t_at)
    tags = data[t_at + 1: t_end].decode()
    return [(addr, tags, data[(t_end + 4) & ~3:])]


def compact(datagram):
    """stream name, frame number, positions blob, timecode ints of a compact output bundle."""
    out = {}
    for addr, tags, args in osc_messages(datagram):
        if addr == "/emoshift/stream":
            end = args.index(b"\0", 4)
            out["stream"] = args[4:end].decode()
        elif addr == "/mocap/frame" and tags == "ihbb":
            n, _t, mlen = struct.unpack_from(">iqI", args, 0)
            at = 16 + ((mlen + 3) & ~3)
            (plen,) = struct.unpack_from(">I", args, at)
            out["frame"] = (n, args[at + 4: at + 4 + plen])
        elif addr == "/mocap/timecode":
            out["timecode"] = struct.unpack(">IIIIi", args)
    return out


# ---- timecode: 29.97 drop-frame, as the SMPTE rule counts it ----

def df_timecode(count):
    fps, d = 30, 2
    per_ten, per_min = fps * 600 - d * 9, fps * 60 - d
    tens, rest = divmod(count, per_ten)
    n = count + d * 9 * tens + (d * ((rest - d) // per_min) if rest >= d else 0)
    return n // 108000 % 24, n // 1800 % 60, n // 30 % 60, n % 30


def packed(hmsf):
    h, m, s, f = hmsf
    return h << 24 | m << 16 | s << 8 | f


# ---- a NatNet server built on python_natnet ----

class Server(threading.Thread):
    """Answers connect, model definitions, echo and FrameRate on 127.0.0.1:port."""

    def __init__(self, info, defs_bytes, rate_reply):
        super().__init__(daemon=True)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.05)
        self.port = self.sock.getsockname()[1]
        self.info, self.defs, self.rate_reply = info, defs_bytes, rate_reply
        self.clients, self.asked_defs, self.stop = [], threading.Event(), False
        self.start()

    def run(self):
        while not self.stop:
            try:
                data, peer = self.sock.recvfrom(65536)
            except socket.timeout:
                continue
            (mid,) = struct.unpack_from("<H", data)
            if mid == 0:  # NAT_CONNECT
                if peer not in self.clients:
                    self.clients.append(peer)
                self.sock.sendto(self.info, peer)
            elif mid == 4:  # NAT_REQUEST_MODELDEF
                self.sock.sendto(self.defs, peer)
                self.asked_defs.set()
            elif mid == 12:  # NAT_ECHOREQUEST
                (stamp,) = struct.unpack_from("<Q", data, 4)
                echo = EchoResponseMessage(request_timestamp=stamp,
                                           received_timestamp=int(time.monotonic() * 1e6))
                self.sock.sendto(serialize(echo), peer)
            elif mid == 2 and data[4:].startswith(b"FrameRate"):
                self.sock.sendto(self.rate_reply, peer)


def frame_rate_reply(hz):
    return struct.pack("<HHf", 3, 4, hz)


def server_info(natnet_version, clock_hz, data_port, multicast):
    msg = ServerInfoMessage(app_name="python_natnet peer", app_version=Version(0, 1),
                            natnet_version=natnet_version,
                            high_resolution_clock_frequency=clock_hz,
                            connection_info=ConnectionInfo(data_port=data_port,
                                                           multicast=multicast,
                                                           multicast_address=GROUP))
    return serialize(msg)


def run(args, **kw):
    return subprocess.run([EMOSHIFT] + args, check=True, stdout=subprocess.PIPE, **kw)


def wait_for(cond, seconds, what):
    end = time.time() + seconds
    while time.time() < end:
        if cond():
            return
        time.sleep(0.02)
    raise SystemExit(f"FAIL setup: {what} within {seconds} s")


# ---- A. a synthetic face over NatNet (python_natnet) and over OSC, into one serve ----

def read_csv(path):
    """Labels and frames (mm floats, None = missing) of an emoshift CSV take."""
    lines = [ln for ln in open(path) if not ln.startswith("#")]
    cols = lines[0].strip().split(",")[2:]
    labels = [c[:-2] for c in cols[::3]]
    frames = []
    for ln in lines[1:]:
        cells = ln.strip().split(",")[2:]
        frames.append([None if cells[i] == "" else float(cells[i]) for i in range(len(cells))])
    return labels, frames


def face_take(work):
    """A synthetic take, its markers renamed Face:<marker> (Motive's export naming), and a
    model trained on it."""
    run(["synth", "--out", f"{work}/session", "--seed", "5", "--sentences", "2",
         "--emotions", "neutral,happy", "--format", "csv"])
    src = f"{work}/session/s01_neutral.csv"
    text = open(src).read().split("\n")
    at = next(i for i, ln in enumerate(text) if ln.startswith("frame,"))
    cells = text[at].split(",")
    text[at] = ",".join(cells[:2] + ["Face:" + c for c in cells[2:]])
    open(f"{work}/face.csv", "w").write("\n".join(text))
    run(["train", f"{work}/face.csv", "--out", f"{work}/model.json", "--components", "8",
         "--restarts", "1", "--head-reference", "none"])
    return read_csv(f"{work}/face.csv")


def collect(sock, got, stop):
    sock.settimeout(0.05)
    while not stop.is_set():
        try:
            got.append(sock.recv(65536))
        except socket.timeout:
            pass


def part_a(work):
    labels, frames = face_take(work)
    names = [label.split(":", 1)[1] for label in labels]
    check("A: the face has 109 markers named Face:<marker>", len(names) == 109, len(names))
    defs = serialize(ModelDefinitionsMessage([MarkersetDescription("Face", names)]))
    data_port = free_port()
    info = server_info(Version(3), 1_000_000, data_port, True)
    server = Server(info, defs, frame_rate_reply(120.0))
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.bind(("127.0.0.1", 0))
    listen, control = free_port(), free_port()
    serve = subprocess.Popen(
        [EMOSHIFT, "serve", "--model", f"{work}/model.json", "--listen", f"127.0.0.1:{listen}",
         "--control", f"127.0.0.1:{control}", "--send", f"127.0.0.1:{rx.getsockname()[1]}",
         "--natnet", f"127.0.0.1:{server.port}", "--natnet-timecode-rate", "29.97df"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    got, stop = [], threading.Event()
    threading.Thread(target=collect, args=(rx, got, stop), daemon=True).start()
    try:
        server.asked_defs.wait(20) or sys.exit("FAIL setup: serve never asked for model defs")
        time.sleep(0.3)
        ctl = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        ctl.bind(("127.0.0.1", 0))
        ctl.settimeout(5)
        for edit in [osc_msg("/component/gain", "if", struct.pack(">if", 0, 1.6)),
                     osc_msg("/emotion/alpha", "if", struct.pack(">if", 1, 1.5))]:
            ctl.sendto(edit, ("127.0.0.1", control))
            reply = ctl.recv(4096)
            check("A: edit confirmed", b"/confirm" in reply.split(b"\0")[0], reply[:40])
        sent = stream_both(labels, frames, listen, data_port)
        time.sleep(0.6)
    finally:
        serve.send_signal(signal.SIGTERM)
        serve.wait(10)
        stop.set()
        server.stop = True
    compare_a(got, sent)


def stream_both(labels, frames, listen, data_port):
    """Each frame at 120 Hz: over NatNet (python_natnet, multicast on loopback) and over OSC
    (labels once a second, then a bundle of /mocap/timecode and /mocap/frame). Returns
    {frame number: (positions blob as the daemon encodes mm, timecode ints)}."""
    mc = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    mc.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton("127.0.0.1"))
    mc.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
    osc = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    osc.bind(("127.0.0.1", 0))
    label_msg = osc_msg("/mocap/labels", "i" + "s" * len(labels),
                        struct.pack(">i", 0) + b"".join(osc_str(lb) for lb in labels))
    sent, start = {}, time.monotonic()
    for k, row in enumerate(frames[:360]):
        n = 1000 + k
        metres = [None if v is None else f32(v / 1000.0) for v in row]
        mm = [float("nan") if v is None else f32(v * 1000.0) for v in metres]
        count = 1790 + k // 4
        hmsf, sub = df_timecode(count), k % 4
        markers = [(0.0, 0.0, 0.0) if metres[i] is None else tuple(metres[i:i + 3])
                   for i in range(0, len(metres), 3)]
        timing = TimingInfo(timecode=packed(hmsf), timecode_subframe=sub, timestamp=n / 120.0,
                            camera_mid_exposure_timestamp=int(time.monotonic() * 1e6),
                            camera_data_received_timestamp=0, transmit_timestamp=0)
        msg = MocapFrameMessage(frame_number=n, markersets=[Markerset("Face", markers)],
                                rigid_bodies=[], skeletons=[], labelled_markers=[],
                                force_plates=[], devices=[], timing_info=timing, params=0)
        mc.sendto(serialize(msg), (GROUP, data_port))
        if k % 120 == 0:
            osc.sendto(label_msg, ("127.0.0.1", listen))
        tc = struct.pack(">IIIIi", packed(hmsf), sub, 30000, 1001, 1 | 2)
        frame = osc_msg("/mocap/frame", "ih" + "f" * len(mm),
                        struct.pack(">iq", n, 0) + struct.pack(f">{len(mm)}f", *mm))
        osc.sendto(osc_bundle(osc_msg("/mocap/timecode", "iiiii", tc), frame),
                   ("127.0.0.1", listen))
        sent[n] = (packed(hmsf), sub)
        time.sleep(max(0.0, start + (k + 1) / 120.0 - time.monotonic()))
    return sent


def compare_a(got, sent):
    streams = {}
    for d in got:
        c = compact(d)
        if "frame" in c:
            streams.setdefault(c.get("stream"), {})[c["frame"][0]] = (c["frame"][1],
                                                                      c.get("timecode"))
    natnet = streams.get("Face", {})
    osc = next((v for k, v in streams.items() if k and k.startswith("127.0.0.1:")), {})
    check("A: every frame over NatNet came out (none lost at 120 Hz)",
          sorted(natnet) == sorted(sent), f"{len(natnet)} of {len(sent)}")
    check("A: every frame over OSC came out", sorted(osc) == sorted(sent),
          f"{len(osc)} of {len(sent)}")
    same = [n for n in sent if n in natnet and n in osc and natnet[n][0] == osc[n][0]]
    check("A: NatNet output equals OSC output, bit for bit, every frame",
          len(same) == len(sent), f"{len(same)} of {len(sent)} equal")
    want = {n: (p, s, 30000, 1001, 3) for n, (p, s) in sent.items()}
    for name, st in [("NatNet", natnet), ("OSC", osc)]:
        ok = [n for n in sent if n in st and st[n][1] == want[n]]
        check(f"A: the 29.97 DF timecode survived over {name}", len(ok) == len(sent),
              f"{len(ok)} of {len(sent)}")
    across = [sent[n] for n in sorted(sent)][36:44]
    check("A: the take crosses a drop-frame minute (00:00:59;29 then 00:01:00;02)",
          across[3][0] == packed((0, 0, 59, 29)) and across[4][0] == packed((0, 1, 0, 2)),
          across)


# ---- B. the real Motive capture served again to emoshift record ----

def capture():
    """Server info, model definitions, FrameRate reply and frames of the Motive 2.1 capture."""
    pcap = os.path.join(SHARED, "motive-2.1/raw/traffic.pcapng")
    info = defs = rate = None
    frames = []
    for _ts, eth in pcapng_packets(pcap):
        p = udp_payload(eth)
        if p is None:
            continue
        sport, _dport, payload = p
        (mid,) = struct.unpack_from("<H", payload)
        if mid == 1 and info is None:
            info = payload
        elif mid == 5 and defs is None:
            defs = payload
        elif mid == 3 and len(payload) == 8 and rate is None:
            rate = payload
        elif mid == 7 and sport == 1511:
            frames.append(payload)
    return info, defs, rate, frames


def part_b(work):
    info, defs, rate, frames = capture()
    check("B: the capture holds 518 frames", len(frames) == 518, len(frames))
    motive = deserialize(info, version=Version(3))
    # Served again on loopback, unicast: frames to the client that connected.
    unicast = server_info(motive.natnet_version, motive.high_resolution_clock_frequency, 0,
                          False)
    server = Server(unicast, defs, rate or frame_rate_reply(120.0))
    out = f"{work}/motive.csv"
    rec = subprocess.Popen([EMOSHIFT, "record", "--natnet", f"127.0.0.1:{server.port}",
                            "--out", out], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        server.asked_defs.wait(20) or sys.exit("FAIL setup: record never asked for model defs")
        time.sleep(0.3)
        sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        start = time.monotonic()
        for k, f in enumerate(frames):
            for client in server.clients:
                sender.sendto(f, client)
            time.sleep(max(0.0, start + (k + 1) / 120.0 - time.monotonic()))
        time.sleep(0.5)
        rec.send_signal(signal.SIGINT)
        stdout, stderr = rec.communicate(timeout=10)
    finally:
        server.stop = True
    check("B: record ends cleanly on Ctrl-C", rec.returncode == 0,
          (rec.returncode, stderr.decode()[-400:]))
    print(stdout.decode().strip(), flush=True)
    compare_b(out)


def compare_b(out):
    lines = open(out).read().splitlines()
    check("B: the announced rate is the file's", lines[0].startswith("# rate_hz=120"), lines[0])
    header = lines[1].split(",")
    rows = {int(r.split(",")[0]): r.split(",") for r in lines[2:]}
    printed = parse_sampleclient(os.path.join(SHARED, "motive-2.1/raw/SampleClient_output.txt"))
    check("B: SampleClient printed 251 frames", len(printed) == 251, len(printed))
    missing, worst, compared = [], 0.0, 0
    for f in printed:
        row = rows.get(int(f["id"]))
        if row is None:
            missing.append(f["id"])
            continue
        for lm in f["labeled"]:
            model, marker, occluded, _pc, _ms, _size, *xyz = lm.split(",")
            if model != "2":
                continue  # unlabelled markers are no markerset's
            col = header.index(f"RaceQuad:Marker{marker}_x")
            cells = row[col: col + 3]
            if occluded == "1":
                worst = max(worst, 1.0) if any(cells) else worst
                continue
            for cell, p in zip(cells, xyz):
                worst = max(worst, abs(float(cell) / 1000.0 - float(p)))
                compared += 1
    check("B: every frame SampleClient printed is in the file", not missing, missing[:5])
    check("B: 251 frames x 5 markers x 3 coordinates compared", compared == 251 * 15, compared)
    check("B: positions match SampleClient's to its printed precision (0.005 m)",
          worst <= 0.005 + 1e-9, worst)


def main():
    with tempfile.TemporaryDirectory() as work:
        part_a(work)
        part_b(work)
    failed = results.count(False)
    print(f"{len(results) - failed} passed, {failed} failed", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
