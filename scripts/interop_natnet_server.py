#!/usr/bin/env python3
"""The NatNet server checks of scripts/interop-natnet-server (run by it, inside a network
namespace whose only interface is loopback). Two independent NatNet clients connect to
`emoshift serve --natnet-server` while an emotion edit runs:

- the `natnet` package from PyPI (NatNet 4: unicast at 4.1, unicast switched to 3.1 with a
  `Bitstream` request, multicast);
- python_natnet (../shared/data/natnet/python_natnet, BSD-3, a NatNet 3 reader; multicast
  only), used from ../shared, never copied.

Each run is fed either by `emoshift replay` (OSC) or by a Motive stand-in (python_natnet's
encoder, 29.97 drop-frame timecode, into `serve --natnet`). Every frame of the daemon's OSC
compact output (`--send`, the truth) must reach the client, with the markerset named after
the performer, the model's marker names, positions within 1e-3 mm, frame numbers and timecode
kept. Then the chain: the real Motive 2.1 capture through a stand-in, `serve --natnet`, out
through `--natnet-server`, into a client: the markerset RaceQuad named, edited, Motive's frame
numbers. Prints PASS/FAIL per check and "N passed, M failed"; exit status 1 on any failure.
"""

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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interop_natnet as base  # noqa: E402  (python_natnet on the path, shared helpers)
from natnet import protocol as pn  # noqa: E402  (python_natnet)
from natnet.comms import Client as PnClient, Connection  # noqa: E402
from natnet.logging import Logger  # noqa: E402


check = base.check
GROUP = "239.255.42.99"


def load_pypi_natnet():
    """The PyPI `natnet` package, imported beside python_natnet (both are called `natnet`)."""
    import importlib.util
    for entry in sys.path:
        if "site-packages" in entry or "dist-packages" in entry:
            init = os.path.join(entry, "natnet", "nat_net_client.py")
            if os.path.exists(init):
                spec = importlib.util.spec_from_file_location(
                    "pypi_natnet", os.path.join(entry, "natnet", "__init__.py"),
                    submodule_search_locations=[os.path.join(entry, "natnet")])
                mod = importlib.util.module_from_spec(spec)
                sys.modules["pypi_natnet"] = mod
                spec.loader.exec_module(mod)
                return mod
    sys.exit("FAIL setup: the PyPI natnet package is not installed")


pypi = load_pypi_natnet()


def port_pair():
    """A command port whose next port (the data port) is free too."""
    for _ in range(100):
        p = base.free_port()
        if p < 65534:
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                s.bind(("127.0.0.1", p + 1))
                s.close()
                return p
            except OSError:
                s.close()
    sys.exit("FAIL setup: no free port pair")


class Daemon:
    """`emoshift serve` with the NatNet server, its OSC compact output collected."""

    def __init__(self, work, model, extra, performer=True):
        self.rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.rx.bind(("127.0.0.1", 0))
        self.listen, self.control, self.command = base.free_port(), base.free_port(), port_pair()
        config = f"{work}/serve.toml"
        with open(config, "w") as f:
            # The OSC replay's stream is the performer Face (a NatNet one is named already).
            f.write('[[performers]]\nname = "Face"\nlayout = 0\n' if performer else "")
        self.proc = subprocess.Popen(
            [base.EMOSHIFT, "serve", "--config", config, "--model", model,
             "--listen", f"127.0.0.1:{self.listen}", "--control", f"127.0.0.1:{self.control}",
             "--send", f"127.0.0.1:{self.rx.getsockname()[1]}",
             "--natnet-server", f"127.0.0.1:{self.command}"] + extra,
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        self.got, self.stop = [], threading.Event()
        threading.Thread(target=base.collect, args=(self.rx, self.got, self.stop),
                         daemon=True).start()
        time.sleep(0.5)

    def edit(self, what, gain=1.6):
        ctl = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        ctl.bind(("127.0.0.1", 0))
        ctl.settimeout(5)
        for msg in [base.osc_msg("/component/gain", "if", struct.pack(">if", 0, gain)),
                    base.osc_msg("/emotion/alpha", "if", struct.pack(">if", 1, 1.5))]:
            ctl.sendto(msg, ("127.0.0.1", self.control))
            reply = ctl.recv(4096)
            check(f"{what}: edit confirmed", b"/confirm" in reply.split(b"\0")[0], reply[:40])

    def status(self):
        ctl = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        ctl.bind(("127.0.0.1", 0))
        ctl.settimeout(5)
        ctl.sendto(base.osc_msg("/status", "", b""), ("127.0.0.1", self.control))
        return ctl.recv(65536)

    def close(self):
        self.proc.send_signal(signal.SIGTERM)
        try:
            _, err = self.proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        self.stop.set()
        return self.proc.returncode, err.decode(errors="replace")

    def truth(self, stream):
        """{frame number: (mm positions or None per marker, timecode ints)} of `stream`."""
        out = {}
        for d in self.got:
            c = base.compact(d)
            if "frame" in c and c.get("stream") == stream:
                n, blob = c["frame"]
                mm = struct.unpack(f">{len(blob) // 4}f", blob)
                out[n] = (mm, c.get("timecode"))
        return out


# ---- the clients ----

class Quiet(Logger):
    """python_natnet's logger, silenced (its clock sync prints a line per echo)."""

    def _log_impl(self, msg, *args):
        pass


class PypiClient:
    """The PyPI `natnet` client (NatNet 4), frames collected by number."""

    def __init__(self, command, multicast=None, bitstream=None):
        kw = dict(server_ip_address="127.0.0.1", local_ip_address="127.0.0.1",
                  command_port=command, use_multicast=multicast is not None)
        if multicast:
            kw.update(multicast_address=multicast[0], data_port=multicast[1])
        self.client = pypi.NatNetClient(**kw)
        self.frames, self.defs, self.errors = {}, [], 0
        self.client.on_data_frame_received_event.handlers.append(self.on_frame)
        self.client.on_data_description_received_event.handlers.append(self.defs.append)
        self.client.connect(timeout=5)
        self.version = self.client.protocol_version
        if bitstream:
            self.client.protocol_version = pypi.Version(*bitstream)
            self.version = self.client.protocol_version
        self.client.request_modeldef()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.spin, daemon=True)
        self.thread.start()

    def on_frame(self, f):
        sets = {m.model_name: m.marker_pos_list for m in f.marker_sets}
        self.frames[f.prefix.frame_number] = (sets, f.suffix.timecode, f.suffix.timecode_sub,
                                              f.labeled_markers)

    def spin(self):
        # Synchronous updates: a datagram that does not decode is counted, not fatal.
        while not self.stop.is_set():
            try:
                self.client.update_sync()
            except Exception:  # noqa: BLE001  (any decode failure of the peer)
                self.errors += 1
            time.sleep(0.002)

    def markerset_names(self):
        return {m.name: tuple(m.marker_names) for m in self.defs[-1].marker_sets} \
            if self.defs else {}

    def close(self):
        # The definitions now that the streams are there (the client asked before any was).
        asked = len(self.defs)
        self.client.request_modeldef()
        end = time.time() + 3
        while len(self.defs) == asked and time.time() < end:
            time.sleep(0.02)
        self.stop.set()
        self.thread.join(2)
        self.client.shutdown()


class PythonNatnetClient:
    """python_natnet (NatNet 3): its connect, clock sync and model definitions, then every
    frame decoded strictly (no byte left over)."""

    def __init__(self, command):
        conn = Connection.open("127.0.0.1", command_port=command)
        conn.send_message(pn.ConnectMessage())
        info, _ = conn.wait_for_message_with_id(pn.MessageId.ServerInfo, timeout=5)
        self.info = info
        client = PnClient._setup_client(conn, info, Quiet())
        self.names = {m.name: tuple(m.marker_names) for m in client._model_definitions
                      if hasattr(m, "marker_names")}
        self.conn, self.frames, self.errors, self.changed = conn, {}, 0, 0
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.spin, daemon=True)
        self.thread.start()

    def spin(self):
        while not self.stop.is_set():
            packet, _ = self.conn.wait_for_packet_raw(timeout=0.05)
            if packet is None or struct.unpack_from("<H", packet)[0] not in (5, 7):
                continue
            try:
                m = pn.deserialize(packet, version=pn.Version(3), strict=True)
            except Exception:  # noqa: BLE001
                self.errors += 1
                continue
            if isinstance(m, pn.ModelDefinitionsMessage):
                self.names = {d.name: tuple(d.marker_names) for d in m.models
                              if hasattr(d, "marker_names")}
                continue
            if m.tracked_models_changed:
                # As python_natnet's Client does: fetch the definitions again.
                self.changed += 1
                self.conn.send_message(pn.RequestModelDefinitionsMessage())
            sets = {s.name: s.markers for s in m.markersets}
            self.frames[m.frame_number] = (sets, m.timing_info.timecode,
                                           m.timing_info.timecode_subframe, m.labelled_markers)

    def markerset_names(self):
        return self.names

    def close(self):
        self.stop.set()
        self.thread.join(2)


# ---- the feeds ----

def feed_replay(work, daemon):
    """`emoshift replay` of the face take into the daemon's OSC socket."""
    base.run(["replay", f"{work}/face.csv", "--to", f"127.0.0.1:{daemon.listen}"])


def motive_stand_in(work, names):
    """python_natnet's Motive stand-in for the face (multicast data port), and its flags."""
    defs = pn.serialize(pn.ModelDefinitionsMessage(
        [base.MarkersetDescription("Face", names)]))
    data_port = base.free_port()
    info = base.server_info(pn.Version(3), 1_000_000, data_port, True)
    server = base.Server(info, defs, base.frame_rate_reply(120.0))
    flags = ["--natnet", f"127.0.0.1:{server.port}", "--natnet-timecode-rate", "29.97df"]
    return server, data_port, flags


# ---- one run ----

def compare(what, daemon, client, stream, names, sent_timecodes=None):
    truth = daemon.truth(stream)
    check(f"{what}: the daemon's OSC output has frames", len(truth) > 100, len(truth))
    got = client.frames
    lost = sorted(set(truth) - set(got))
    check(f"{what}: every edited frame arrives ({len(truth)})", not lost,
          f"{len(lost)} lost, first {lost[:5]}")
    defs = client.markerset_names()
    check(f"{what}: the markerset is named Face with the model's marker names in order",
          defs.get("Face") == tuple(names), list(defs.items())[:1])
    worst, compared, nan_ok = 0.0, 0, True
    for n, (mm, _tc) in truth.items():
        if n not in got:
            continue
        sets = got[n][0]
        markers = sets.get("Face")
        if markers is None or len(markers) * 3 != len(mm):
            worst = math.inf
            continue
        for i, p in enumerate(markers):
            if any(math.isnan(c) for c in p):
                nan_ok &= all(math.isnan(c) for c in p)
                continue
            for c, want in zip(p, mm[3 * i:3 * i + 3]):
                worst = max(worst, abs(c * 1000.0 - want))
                compared += 1
    check(f"{what}: positions equal the OSC compact output within 1e-3 mm "
          f"({compared} coordinates)", compared > 0 and worst <= 1e-3 and nan_ok, worst)
    labelled = [lm for n in got for lm in got[n][3]]
    check(f"{what}: labelled markers carry the model id and 1-based marker ids",
          labelled and all((getattr(lm, "model_id", None) or lm.id_num >> 16) == 1
                           for lm in labelled[:500]), labelled[:1])
    if sent_timecodes is not None:
        ok = [n for n, (p, s) in sent_timecodes.items()
              if n in got and (got[n][1], got[n][2]) == (p, s)]
        check(f"{what}: frame numbers and timecode (29.97 DF) kept", len(ok) == len(
            sent_timecodes), f"{len(ok)} of {len(sent_timecodes)}")
    check(f"{what}: the client decoded every datagram", client.errors == 0, client.errors)
    if isinstance(client, PythonNatnetClient):
        check(f"{what}: the stream's arrival flagged 'tracked models changed' and the client "
              "fetched the definitions again", client.changed > 0, client.changed)


def run_case(work, what, feed, client_kind, server_extra):
    labels, frames = work["take"]
    names = [lb.split(":", 1)[1] for lb in labels]
    motive = feed == "motive"
    flags = list(server_extra)
    server = None
    if motive:
        server, data_port, natnet_flags = motive_stand_in(work["dir"], names)
        flags += natnet_flags
    daemon = Daemon(work["dir"], work["model"], flags)
    client = None
    try:
        daemon.edit(what)
        multicast = None
        if "--natnet-server-multicast" in flags:
            group = flags[flags.index("--natnet-server-multicast") + 1]
            multicast = (group.split(":")[0], int(group.split(":")[1]))
        if client_kind == "python_natnet":
            client = PythonNatnetClient(daemon.command)
        elif client_kind == "pypi-3.1":
            client = PypiClient(daemon.command, bitstream=(3, 1))
        else:
            client = PypiClient(daemon.command, multicast=multicast)
        time.sleep(0.3)
        sent = None
        if motive:
            server.asked_defs.wait(20) or sys.exit("FAIL setup: serve never asked for defs")
            time.sleep(0.3)
            # Its OSC copy goes to a port nobody binds: the NatNet stream alone is served.
            sent = base.stream_both(labels, frames, base.free_port(), data_port)
        else:
            feed_replay(work["dir"], daemon)
        time.sleep(0.8)
        status = daemon.status()
        check(f"{what}: /status has natnet_server/frames_sent", b"natnet_server/frames_sent"
              in status, status[:60])
    finally:
        if client:
            client.close()
        code, err = daemon.close()
        if server:
            server.stop = True
    check(f"{what}: serve stops cleanly", code == 0, err[-400:])
    compare(what, daemon, client, "Face", names, sent)


# ---- the chain: the real Motive capture through serve --natnet and --natnet-server ----

def chain(work):
    info, defs, rate, frames = base.capture()
    motive = base.deserialize(info, version=base.Version(3))
    unicast = base.server_info(motive.natnet_version, motive.high_resolution_clock_frequency, 0,
                               False)
    # A model of RaceQuad's five markers, trained on the capture recorded by emoshift.
    server = base.Server(unicast, defs, rate or base.frame_rate_reply(120.0))
    take = f"{work['dir']}/racequad.csv"
    rec = subprocess.Popen([base.EMOSHIFT, "record", "--natnet", f"127.0.0.1:{server.port}",
                            "--out", take], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    server.asked_defs.wait(20) or sys.exit("FAIL setup: record never asked for model defs")
    time.sleep(0.3)
    play(server, frames)
    rec.send_signal(signal.SIGINT)
    rec.communicate(timeout=10)
    server.stop = True
    model = f"{work['dir']}/racequad.json"
    base.run(["train", take, "--out", model, "--components", "3", "--restarts", "1",
              "--head-reference", "none"])
    server = base.Server(unicast, defs, rate or base.frame_rate_reply(120.0))
    server.asked_defs.clear()
    daemon = Daemon(work["dir"], model, ["--natnet", f"127.0.0.1:{server.port}"],
                    performer=False)
    try:
        server.asked_defs.wait(20) or sys.exit("FAIL setup: serve never asked for defs")
        daemon.edit("chain", gain=8.0)
        client = PypiClient(daemon.command)
        time.sleep(0.3)
        play(server, frames)
        time.sleep(0.8)
        client.close()
    finally:
        code, err = daemon.close()
        server.stop = True
    check("chain: serve stops cleanly", code == 0, err[-400:])
    motive_numbers = {struct.unpack_from("<i", f, 4)[0] for f in frames}
    got = client.frames
    truth = daemon.truth("RaceQuad")
    check("chain: the markerset arrives named RaceQuad with Motive's marker names",
          client.markerset_names().get("RaceQuad") == tuple(f"Marker{i}" for i in range(1, 6)),
          client.markerset_names())
    check(f"chain: every edited frame arrives ({len(truth)}), numbered as Motive numbered it",
          truth and set(truth) <= set(got) and set(got) <= motive_numbers,
          (len(truth), len(got), sorted(set(got) - motive_numbers)[:3]))
    edited = 0.0
    captured = {struct.unpack_from("<i", f, 4)[0]: f for f in frames}
    for n, (sets, *_rest) in got.items():
        rq = sets.get("RaceQuad")
        raw = pn.deserialize(captured[n], version=pn.Version(3)) if n in captured else None
        if rq is None or raw is None:
            continue
        # Motive streamed RaceQuad (rigid body 2) as labelled markers only.
        src = {lm.marker_id: lm.position for lm in raw.labelled_markers if lm.model_id == 2}
        for i, p in enumerate(rq):
            q = src.get(i + 1)
            if q is not None and not any(math.isnan(c) for c in p):
                edited = max(edited, max(abs(a - b) for a, b in zip(p, q)))
    check("chain: the markers are edited (differ from Motive's by > 0.1 mm somewhere)",
          edited > 1e-4, edited)


def play(server, frames):
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    start = time.monotonic()
    for k, f in enumerate(frames):
        for client in list(server.clients):
            sender.sendto(f, client)
        time.sleep(max(0.0, start + (k + 1) / 120.0 - time.monotonic()))


def main():
    with tempfile.TemporaryDirectory() as d:
        take = base.face_take(d)
        work = {"dir": d, "take": take, "model": f"{d}/model.json"}
        mc = f"{GROUP}:{base.free_port()}"
        cases = [
            ("natnet 4.1 unicast, replay", "replay", "pypi", []),
            ("natnet 3.1 unicast (Bitstream), Motive stand-in", "motive", "pypi-3.1", []),
            ("natnet 4.1 multicast, Motive stand-in", "motive", "pypi",
             ["--natnet-server-multicast", mc]),
            ("python_natnet 3.1 multicast, replay", "replay", "python_natnet",
             ["--natnet-server-multicast", mc, "--natnet-server-version", "3.1"]),
        ]
        only = os.environ.get("ONLY")
        for what, feed, kind, extra in cases:
            if only and only not in what:
                continue
            run_case(work, what, feed, kind, extra)
        if not only or only == "chain":
            chain(work)
    failed = base.results.count(False)
    print(f"{len(base.results) - failed} passed, {failed} failed", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
