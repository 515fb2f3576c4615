#!/usr/bin/env python3
"""The QTM checks of scripts/interop-qtm (run by it, loopback only). The peer is `qtm-rt`, the
official Qualisys RT SDK for Python (PyPI, MIT): what it accepts, QTM Connect's C++ SDK reads
the same way.

Output: `emoshift serve --qtm-server` fed by `emoshift replay` (a synthetic face) with an
emotion edit running. qtm-rt connects (protocol 1.25), asks the version, byte order, state;
learns the labels from `GetParameters All` after the "parameters changed" event; is refused
`TakeControl` with QTM's error packet; streams `3D` + `3DRes` over TCP on one connection and
over UDP on another. Every frame the daemon's OSC compact output (`--send`, the truth) carries
must reach both, with positions equal within 1e-3 mm and missing markers NaN.

Chain: that server (fed by replay, proven above) is the QTM stand-in. `emoshift record --qtm`
from it writes the frames it served; `serve --qtm` takes them live, edits them and serves them
again through its own `--qtm-server` to qtm-rt, QTM's frame numbers kept.

Timecode chain: scripts/qtm_stand_in.py serves the take stamped SMPTE, then IRIG (accepted
first by qtm-rt: frames, positions and timecode as served); `serve --qtm` from it serves them
on through `--qtm-server`, and qtm-rt there reads each frame's timecode as the stand-in sent
it, SMPTE and IRIG; the OSC output carries the SMPTE frames' timecode and none for IRIG.

Discovery: in the private network namespace interop-qtm makes, a veth pair with a default
route makes 255.255.255.255 reachable; `serve --qtm-server 0.0.0.0:PORT` answers qtm-rt's
`Discover` with QTM's base port (PORT - 1) from the namespace's address. Without root (no
namespace) or without veth it prints SKIP with the reason; it never binds beyond loopback on
the host.

Prints PASS/FAIL per check and "N passed, M failed"; exit status 1 on any failure.
"""

import asyncio
import math
import os
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time

import qtm_rt
from qtm_rt.packet import QRTComponentType, QRTEvent, QRTPacket

from qtm_stand_in import StandIn, same_positions, tc_of

EMOSHIFT = os.environ["EMOSHIFT"]
results = []


def check(name, ok, detail=""):
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else ": " + str(detail)), flush=True)
    results.append(bool(ok))


def free_port(kind=socket.SOCK_DGRAM):
    s = socket.socket(socket.AF_INET, kind)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def run(args):
    return subprocess.run([EMOSHIFT] + args, check=True, stdout=subprocess.PIPE)


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
    t_at = (a_end + 4) & ~3
    t_end = data.index(b"\0", t_at)
    return [(data[:a_end].decode(), data[t_at + 1: t_end].decode(), data[(t_end + 4) & ~3:])]


def osc_msg(addr, tags, payload):
    def pad(s):
        b = s.encode() + b"\0"
        return b + b"\0" * (-len(b) % 4)
    return pad(addr) + pad("," + tags) + payload


def truth_of(datagrams):
    """{frame number: mm positions} of the daemon's compact output."""
    out = {}
    for d in datagrams:
        for addr, tags, args in osc_messages(d):
            if addr == "/mocap/frame" and tags == "ihbb":
                n, _t, mlen = struct.unpack_from(">iqI", args, 0)
                at = 16 + ((mlen + 3) & ~3)
                (plen,) = struct.unpack_from(">I", args, at)
                blob = args[at + 4: at + 4 + plen]
                out[n] = struct.unpack(f">{len(blob) // 4}f", blob)
    return out


def collect(sock, got, stop):
    sock.settimeout(0.05)
    while not stop.is_set():
        try:
            got.append(sock.recv(65536))
        except socket.timeout:
            pass


def take(work):
    run(["synth", "--out", f"{work}/session", "--seed", "5", "--sentences", "2",
         "--emotions", "neutral,happy", "--format", "csv"])
    src = f"{work}/session/s01_neutral.csv"
    run(["train", src, "--out", f"{work}/model.json", "--components", "8",
         "--restarts", "1", "--head-reference", "none"])
    header = next(ln for ln in open(src) if ln.startswith("frame,"))
    return src, [c[:-2] for c in header.strip().split(",")[2::3]]


class Daemon:
    """`emoshift serve --qtm-server`, its OSC compact output collected."""

    def __init__(self, work, model, extra=(), qtm_ip="127.0.0.1"):
        self.rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.rx.bind(("127.0.0.1", 0))
        self.listen, self.control = free_port(), free_port()
        self.qtm = free_port(socket.SOCK_STREAM)
        self.proc = subprocess.Popen(
            [EMOSHIFT, "serve", "--model", model,
             "--listen", f"127.0.0.1:{self.listen}", "--control", f"127.0.0.1:{self.control}",
             "--send", f"127.0.0.1:{self.rx.getsockname()[1]}",
             "--qtm-server", f"{qtm_ip}:{self.qtm}"] + list(extra),
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        self.got, self.stop = [], threading.Event()
        threading.Thread(target=collect, args=(self.rx, self.got, self.stop), daemon=True).start()
        time.sleep(0.5)

    def control_msg(self, msg):
        ctl = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        ctl.bind(("127.0.0.1", 0))
        ctl.settimeout(5)
        ctl.sendto(msg, ("127.0.0.1", self.control))
        return ctl.recv(65536)

    def edit(self):
        for msg in [osc_msg("/component/gain", "if", struct.pack(">if", 0, 1.6)),
                    osc_msg("/emotion/alpha", "if", struct.pack(">if", 1, 1.5))]:
            reply = self.control_msg(msg)
            check("edit confirmed", b"/confirm" in reply.split(b"\0")[0], reply[:40])

    def close(self):
        self.proc.send_signal(signal.SIGTERM)
        try:
            _, err = self.proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        self.stop.set()
        return self.proc.returncode, err.decode(errors="replace")


def frames_of(packet, into):
    """3D and 3DRes positions of a qtm-rt packet, by frame number."""
    if QRTComponentType.Component3d in packet.components:
        _, markers = packet.get_3d_markers()
        into.setdefault("3d", {})[packet.framenumber] = [(m.x, m.y, m.z) for m in markers]
    if QRTComponentType.Component3dRes in packet.components:
        _, markers = packet.get_3d_markers_residual()
        into.setdefault("3dres", {})[packet.framenumber] = [(m.x, m.y, m.z) for m in markers]


class Udp(asyncio.DatagramProtocol):
    def __init__(self, into):
        self.into, self.errors = into, 0

    def datagram_received(self, data, addr):
        try:
            size, kind = struct.unpack_from("<II", data, 0)
            assert kind == 3 and size == len(data)
            frames_of(QRTPacket(data[8:]), self.into)
        except Exception:  # noqa: BLE001  (counted: every datagram must decode)
            self.errors += 1


async def clients(daemon, feed):
    events = []
    tcp = await qtm_rt.connect("127.0.0.1", port=daemon.qtm, version="1.25",
                               on_event=events.append)
    check("qtm-rt connects and agrees version 1.25", tcp is not None)
    if tcp is None:
        return None
    check("QTMVersion answered", (await tcp.qtm_version()).startswith(b"QTM Version is"))
    check("byte order little endian", await tcp.byte_order() == b"Byte order is little endian")
    state = await tcp.get_state()
    check("GetState answered with an event", isinstance(state, QRTEvent), state)
    try:
        await tcp.take_control("anything")
        check("TakeControl refused with an error packet", False, "accepted")
    except qtm_rt.QRTCommandException as e:
        check("TakeControl refused with an error packet", b"refused" in str(e).encode(), e)
    udp_conn = await qtm_rt.connect("127.0.0.1", port=daemon.qtm, version="1.25")
    loop = asyncio.get_running_loop()
    got_udp = {}
    transport, udp = await loop.create_datagram_endpoint(lambda: Udp(got_udp),
                                                         local_addr=("127.0.0.1", 0))
    port = transport.get_extra_info("sockname")[1]
    feed.start()
    await tcp.await_event(QRTEvent.EventCameraSettingsChanged, timeout=20)
    check("'parameters changed' event when the performer stream appears", True)
    xml = (await tcp.get_parameters(["all"])).decode()
    labels = [x.split("</Name>")[0] for x in xml.split("<Name>")[1:]]
    check("GetParameters All: QTM_Parameters_Ver_1.25 with the frequency",
          xml.startswith("<QTM_Parameters_Ver_1.25>") and "<Frequency>120</Frequency>" in xml,
          xml[:200])
    got_tcp = {}
    await tcp.stream_frames(frames="allframes", components=["3d", "3dres"],
                            on_packet=lambda p: frames_of(p, got_tcp))
    await udp_conn._protocol.send_command(f"streamframes allframes udp:{port} 3d 3dres",
                                          callback=False)
    await asyncio.sleep(0.3)
    while feed.is_alive():
        await asyncio.sleep(0.1)
    await asyncio.sleep(0.8)
    await tcp.stream_frames_stop()
    tcp.disconnect()
    udp_conn.disconnect()
    transport.close()
    check("every UDP datagram decodes as a QTM data packet", udp.errors == 0, udp.errors)
    return labels, got_tcp, got_udp


def compare(what, truth, got, n_labels):
    lost = sorted(set(truth) - set(got))
    # The client subscribes once the stream is announced: the first frames go before.
    first = min(got) if got else None
    lost = [n for n in lost if first is None or n >= first]
    check(f"{what}: every edited frame after the subscription arrives ({len(got)})",
          got and not lost, f"{len(lost)} lost, first {lost[:5]}")
    worst, compared, shape = 0.0, 0, True
    for n, markers in got.items():
        mm = truth.get(n)
        if mm is None:
            continue
        shape &= len(markers) == n_labels and len(mm) == 3 * n_labels
        for i, p in enumerate(markers):
            if any(math.isnan(c) for c in p):
                continue
            for c, want in zip(p, mm[3 * i:3 * i + 3]):
                worst = max(worst, abs(c - want))
                compared += 1
    check(f"{what}: positions equal the OSC compact output within 1e-3 mm "
          f"({compared} coordinates)", shape and compared > 0 and worst <= 1e-3, worst)


def output(work):
    src, labels = take(work)
    daemon = Daemon(work, f"{work}/model.json")
    try:
        daemon.edit()
        feed = threading.Thread(target=run, args=(["replay", src, "--to",
                                                   f"127.0.0.1:{daemon.listen}"],))
        got = asyncio.run(clients(daemon, feed))
        status = daemon.control_msg(osc_msg("/status", "", b""))
        check("/status has qtm_server/frames_sent", b"qtm_server/frames_sent" in status)
    finally:
        code, err = daemon.close()
    check("serve stops cleanly", code == 0, err[-400:])
    if got is None:
        return
    served, got_tcp, got_udp = got
    check("the labels are the model's markers, in order", served == labels,
          (served[:3], labels[:3]))
    truth = truth_of(daemon.got)
    check("the daemon's OSC output has frames", len(truth) > 100, len(truth))
    for what, into in [("TCP", got_tcp), ("UDP", got_udp)]:
        for comp in ["3d", "3dres"]:
            compare(f"{what} {comp}", truth, into.get(comp, {}), len(labels))


async def stream_numbers(port, seconds_idle=1.5):
    """qtm-rt streams 3D over TCP from `port` until frames stop: {frame number: positions}."""
    conn = await qtm_rt.connect("127.0.0.1", port=port, version="1.25")
    if conn is None:
        return None
    got, last = {}, [time.time()]

    def on_packet(p):
        frames_of(p, got)
        last[0] = time.time()
    await conn.await_event(QRTEvent.EventCameraSettingsChanged, timeout=20)
    await conn.stream_frames(frames="allframes", components=["3d"], on_packet=on_packet)
    while time.time() - last[0] < seconds_idle:
        await asyncio.sleep(0.1)
    conn.disconnect()
    return got.get("3d", {})


def read_csv(path):
    """{frame number: mm positions (NaN for gaps)} of an emoshift CSV take."""
    out = {}
    for ln in open(path):
        if ln.startswith("#") or ln.startswith("frame,"):
            continue
        cells = ln.strip().split(",")
        out[int(cells[0])] = [math.nan if c == "" else float(c) for c in cells[2:]]
    return out


def chain(work):
    src, labels = f"{work}/session/s01_neutral.csv", None
    stand_in = Daemon(work, f"{work}/model.json")
    edited = Daemon(work, f"{work}/model.json", ["--qtm", f"127.0.0.1:{stand_in.qtm}"])
    rec = subprocess.Popen([EMOSHIFT, "record", "--qtm", f"127.0.0.1:{stand_in.qtm}",
                            "--out", f"{work}/rec.csv", "--seconds", "3"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        edited.edit()
        time.sleep(0.5)
        feed = threading.Thread(target=run, args=(["replay", src, "--to",
                                                   f"127.0.0.1:{stand_in.listen}"],))
        feed.start()
        got = asyncio.run(stream_numbers(edited.qtm))
        feed.join()
        out, err = rec.communicate(timeout=20)
        check("record --qtm ends by itself and writes the take", rec.returncode == 0,
              err.decode(errors="replace")[-400:])
    finally:
        edited_code, edited_err = edited.close()
        code, err = stand_in.close()
    check("both daemons stop cleanly", code == 0 and edited_code == 0,
          (err[-300:], edited_err[-300:]))
    served = truth_of(stand_in.got)
    recorded = read_csv(f"{work}/rec.csv") if os.path.exists(f"{work}/rec.csv") else {}
    common = [n for n in recorded if n in served]
    worst = max((abs(a - b) for n in common for a, b in zip(recorded[n], served[n])
                 if not math.isnan(a)), default=math.inf)
    check(f"record --qtm: the frames the stand-in served, QTM's numbers ({len(common)} frames)",
          len(common) > 100 and len(common) == len(recorded), (len(common), len(recorded)))
    check("record --qtm: positions as served within 1e-3 mm", worst <= 1e-3, worst)
    truth = truth_of(edited.got)
    check("serve --qtm: the edited daemon processed the stand-in's frames", len(truth) > 100,
          len(truth))
    check("serve --qtm: its frames keep the stand-in's frame numbers",
          truth and set(truth) <= set(served), sorted(set(truth) - set(served))[:5])
    moved = max((abs(a - b) for n in truth if n in served
                 for a, b in zip(truth[n], served[n])), default=0.0)
    check("serve --qtm: the edit changes the face live", moved > 0.01, moved)
    if got is None:
        check("chain: qtm-rt connects to the edited daemon's --qtm-server", False)
        return
    compare("chain (stand-in -> serve --qtm -> --qtm-server -> qtm-rt)", truth, got,
            len(next(iter(got.values()))) if got else 0)


async def stream_timecodes(port, start=None, seconds_idle=1.5):
    """qtm-rt streams 3D and Timecode over TCP from `port` (then `start()`s the source) until
    frames stop: {frame number: (flat positions, (type, hi, lo) or None)}."""
    conn = await qtm_rt.connect("127.0.0.1", port=port, version="1.25")
    if conn is None:
        return None
    got, last = {}, [time.time()]

    def on_packet(p):
        _, markers = p.get_3d_markers()
        got[p.framenumber] = ([c for m in markers for c in (m.x, m.y, m.z)], tc_of(p))
        last[0] = time.time()
    streaming = asyncio.ensure_future(
        conn.stream_frames(frames="allframes", components=["3d", "timecode"],
                           on_packet=on_packet))
    await asyncio.sleep(0.3)
    if start:
        start()
    await streaming
    while time.time() - last[0] < seconds_idle:
        await asyncio.sleep(0.1)
    await conn.stream_frames_stop()
    conn.disconnect()
    return got


def osc_timecodes(datagrams):
    """{frame number: /mocap/timecode (packed, sub, num, den, flags) or None} of the compact
    output."""
    out = {}
    for d in datagrams:
        msgs = osc_messages(d)
        tc = next((struct.unpack(">IIIIi", a) for n, t, a in msgs if n == "/mocap/timecode"),
                  None)
        for addr, tags, args in msgs:
            if addr == "/mocap/frame":
                out[struct.unpack_from(">i", args, 0)[0]] = tc
    return out


def check_timecodes(what, served, got, wanted):
    """Every frame `got` has the stand-in's timecode; enough of both kinds arrive."""
    wrong = [n for n, (_, tc) in got.items() if n not in served or tc != served[n][1]]
    kinds = {k: sum(1 for n, (_, tc) in got.items() if tc and tc[0] == k) for k in (0, 1)}
    check(f"{what}: every frame's timecode is the stand-in's ({kinds[0]} SMPTE, "
          f"{kinds[1]} IRIG)", got and not wrong and min(kinds.values()) > 0.3 * wanted,
          (len(got), wrong[:5], kinds))


async def timecode_chain_async(work, labels, frames):
    stand_in = StandIn(labels, frames)
    port = await stand_in.start()
    stand_in.go.set()
    direct = await stream_timecodes(port)
    check("stand-in: qtm-rt streams every frame it serves",
          direct is not None and sorted(direct) == sorted(stand_in.served),
          (len(direct or {}), len(stand_in.served)))
    check("stand-in: positions as served",
          direct and all(same_positions(p, stand_in.served[n][0]) for n, (p, _) in direct.items()))
    check_timecodes("stand-in (qtm-rt)", stand_in.served, direct or {}, len(frames) // 2)
    stand_in.go.clear()
    daemon = Daemon(work, f"{work}/model.json", ["--qtm", f"127.0.0.1:{port}"])
    try:
        got = await stream_timecodes(daemon.qtm, start=stand_in.go.set)
    finally:
        code, err = daemon.close()
        stand_in.close()
    check("timecode chain: serve --qtm stops cleanly", code == 0, err[-400:])
    check_timecodes("timecode chain (stand-in -> serve --qtm -> --qtm-server -> qtm-rt)",
                    stand_in.served, got or {}, len(frames) // 2)
    osc = osc_timecodes(daemon.got)
    bad = []
    for n, tc in osc.items():
        kind, _, lo = stand_in.served[n][1]
        want = None if kind == 1 else (
            (lo & 0x1f) << 24 | (lo >> 5 & 0x3f) << 16 | (lo >> 11 & 0x3f) << 8 | lo >> 17 & 0x1f,
            lo >> 22 & 0x1ff)
        if (tc[:2] if tc and tc[4] & 1 else None) != want:
            bad.append((n, tc, want))
    check(f"timecode chain: the OSC output says SMPTE as SMPTE and nothing for IRIG "
          f"({len(osc)} frames)", len(osc) > 100 and not bad, bad[:3])


def timecode_chain(work):
    src = f"{work}/session/s01_neutral.csv"
    header = next(ln for ln in open(src) if ln.startswith("frame,"))
    labels = [c[:-2] for c in header.strip().split(",")[2::3]]
    rows = read_csv(src)
    frames = [rows[n] for n in sorted(rows)][:360]
    asyncio.run(timecode_chain_async(work, labels, frames))


VETH = [["link", "add", "qtmd0", "type", "veth", "peer", "name", "qtmd1"],
        ["addr", "add", "10.77.0.1/24", "dev", "qtmd0"],
        ["addr", "add", "10.77.0.2/24", "dev", "qtmd1"],
        ["link", "set", "qtmd0", "up"], ["link", "set", "qtmd1", "up"],
        ["route", "add", "default", "dev", "qtmd0"]]


def broadcast_net():
    """In the private namespace interop-qtm made: a veth pair and a default route, so that
    255.255.255.255 is reachable. None when it works, else why not (the command, its error)."""
    if os.environ.get("EMOSHIFT_PRIVATE_NETNS") != "1":
        return "not in a private network namespace (interop-qtm needs root for unshare --net)"
    for args in VETH:
        r = subprocess.run(["ip"] + args, capture_output=True, text=True)
        if r.returncode != 0:
            return f"`ip {' '.join(args)}`: {r.stderr.strip()}"
    return None


async def discover_all():
    return [r async for r in qtm_rt.Discover("0.0.0.0")]


def discovery(work):
    """qtm-rt's Discover broadcasts to 255.255.255.255:22226 and finds `serve --qtm-server
    0.0.0.0:PORT` with QTM's base port (PORT - 1) from the namespace's own address."""
    why = broadcast_net()
    if why:
        print(f"SKIP discovery (no broadcast network here): {why}", flush=True)
        return
    daemon = Daemon(work, f"{work}/model.json", ["--control-allow", "127.0.0.0/8,10.77.0.0/24"],
                    qtm_ip="0.0.0.0")
    port = daemon.qtm
    try:
        found = asyncio.run(discover_all())

        async def connect(host, base):
            conn = await qtm_rt.connect(host, port=base + 1, version="1.25")
            ok = conn is not None and (await conn.qtm_version()).startswith(b"QTM Version is")
            if conn is not None:
                conn.disconnect()
            return ok
        ours = [r for r in found if r.info.startswith(b"emoshift ")]
        check("discovery: qtm-rt's Discover finds emoshift once", len(ours) == 1, found)
        if ours:
            r = ours[0]
            check("discovery: QTM's base port (the RT port - 1) and the namespace's address",
                  r.port == port - 1 and r.host in ("10.77.0.1", "10.77.0.2"), r)
            check("discovery: qtm-rt connects to the base port + 1 at the discovered host",
                  asyncio.run(connect(r.host, r.port)))
    finally:
        code, err = daemon.close()
    check("discovery: serve stops cleanly", code == 0, err[-400:])


def main():
    with tempfile.TemporaryDirectory() as work:
        output(work)
        chain(work)
        timecode_chain(work)
        discovery(work)
    passed = sum(results)
    print(f"{passed} passed, {len(results) - passed} failed")
    sys.exit(0 if passed == len(results) else 1)


if __name__ == "__main__":
    main()
