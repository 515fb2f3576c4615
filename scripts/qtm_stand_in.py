"""A QTM stand-in for scripts/interop_qtm.py that serves a take with SMPTE and IRIG timecode.

emoshift's own `--qtm-server` serves the source's timecode, but no emoshift source can stamp
IRIG except QTM itself, so this small RT server (protocol 1.25, little endian) stands in for a
QTM synchronised to a timecode clock. It answers what a streaming client asks (welcome,
`Version`, `QTMVersion`, `ByteOrder`, `GetState`, `GetParameters`, `StreamFrames AllFrames`
over TCP with `3D` and `Timecode`, `StreamFrames Stop`, `Disconnect`) and refuses the rest with
an error packet. Each client that starts streaming gets the whole take from its first frame, at
the take's rate: the first half stamped SMPTE, the second half IRIG, so one stream proves both
and that a sink does not keep a stale kind. Accepted first by qtm-rt (see `accepted`).
"""

import asyncio
import math
import struct

PACKET_ERROR, PACKET_COMMAND, PACKET_XML, PACKET_DATA, PACKET_EVENT = 0, 1, 2, 3, 6
COMPONENT_3D, COMPONENT_TIMECODE = 1, 17
EVENT_CONNECTED = 1
FIRST_FRAME = 5000


def packet(kind, payload):
    return struct.pack("<II", 8 + len(payload), kind) + payload


def text(kind, s):
    return packet(kind, s.encode() + b"\0")


def smpte_words(i, per=4):
    """SMPTE 10:00:00:00 at 30 fps, `per` capture frames per timecode frame."""
    count, sub = divmod(i, per)
    frames, secs = count % 30, count // 30
    lo = 10 | (secs // 60) << 5 | (secs % 60) << 11 | frames << 17 | sub << 22
    return (0, 0, lo)


def irig_words(i, rate_hz=120):
    """IRIG year 26, day 332, 08:59:30.0 plus take time (the take is shorter than 30 s)."""
    tenths_total = i * 10 // rate_hz
    secs, tenths = divmod(tenths_total, 10)
    hi = 26 | 332 << 7
    lo = 8 | 59 << 5 | (30 + secs) << 11 | tenths << 17
    return (1, hi, lo)


def timecode(i, n):
    """(type, high word, low word) the stand-in stamps on frame index `i` of `n`."""
    return smpte_words(i) if i < n // 2 else irig_words(i - n // 2)


class StandIn:
    """Serves `frames` (lists of x y z per label, NaN missing) under `labels` at `rate_hz`."""

    def __init__(self, labels, frames, rate_hz=120):
        self.labels, self.frames, self.rate_hz = labels, frames, rate_hz
        self.served = {}  # frame number -> (positions, timecode words)
        for i, f in enumerate(frames):
            self.served[FIRST_FRAME + i] = (f, timecode(i, len(frames)))
        self.server = None
        self.go = asyncio.Event()  # streams start when set (a test subscribes downstream first)

    async def start(self):
        self.server = await asyncio.start_server(self.client, "127.0.0.1", 0)
        return self.server.sockets[0].getsockname()[1]

    def close(self):
        self.server.close()

    def parameters(self):
        names = "".join(f"<Label><Name>{n}</Name></Label>" for n in self.labels)
        return ("<QTM_Parameters_Ver_1.25><General><Frequency>"
                f"{self.rate_hz}</Frequency></General><The_3D>{names}</The_3D>"
                "</QTM_Parameters_Ver_1.25>")

    def data(self, number):
        positions, (kind, hi, lo) = self.served[number]
        d3 = struct.pack("<IHH", len(self.labels), 0, 0) + struct.pack(
            f"<{len(positions)}f", *positions)
        tc = struct.pack("<IIII", 1, kind, hi, lo)
        comps = [struct.pack("<II", 8 + len(d3), COMPONENT_3D) + d3,
                 struct.pack("<II", 8 + len(tc), COMPONENT_TIMECODE) + tc]
        t_us = (number - FIRST_FRAME) * 1_000_000 // self.rate_hz
        return packet(PACKET_DATA, struct.pack("<qII", t_us, number, len(comps)) + b"".join(comps))

    async def stream(self, writer):
        await self.go.wait()
        start = asyncio.get_running_loop().time()
        for i, number in enumerate(sorted(self.served)):
            await asyncio.sleep(max(0.0, start + i / self.rate_hz
                                    - asyncio.get_running_loop().time()))
            writer.write(self.data(number))
            await writer.drain()

    async def client(self, reader, writer):
        writer.write(text(PACKET_COMMAND, "QTM RT Interface connected"))
        streaming = None
        try:
            while True:
                head = await reader.readexactly(8)
                size, _kind = struct.unpack("<II", head)
                cmd = (await reader.readexactly(size - 8)).rstrip(b"\0").decode()
                word = cmd.split(" ")[0].lower()
                if word == "version":
                    writer.write(text(PACKET_COMMAND, f"Version set to {cmd.split(' ')[1]}"))
                elif word == "qtmversion":
                    writer.write(text(PACKET_COMMAND, "QTM Version is stand-in 1.0"))
                elif word == "byteorder":
                    writer.write(text(PACKET_COMMAND, "Byte order is little endian"))
                elif word == "getstate":
                    writer.write(packet(PACKET_EVENT, bytes([EVENT_CONNECTED])))
                elif word == "getparameters":
                    writer.write(text(PACKET_XML, self.parameters()))
                elif cmd.lower() == "streamframes stop":
                    if streaming:
                        streaming.cancel()
                elif word == "streamframes" and "udp" not in cmd.lower():
                    streaming = asyncio.ensure_future(self.stream(writer))
                elif word == "disconnect":
                    break
                else:
                    writer.write(text(PACKET_ERROR, f"Command not supported by the stand-in: {cmd}"))
                await writer.drain()
        except (asyncio.IncompleteReadError, ConnectionError, asyncio.CancelledError):
            pass  # the client left, or the test ended the stand-in
        finally:
            if streaming:
                streaming.cancel()
            writer.close()


def tc_of(packet):
    """(type, hi, lo) of a qtm-rt packet's first timecode, or None."""
    from qtm_rt.packet import QRTComponentType
    if QRTComponentType.ComponentTimecode not in packet.components:
        return None
    _, tcs = packet.get_timecode()
    return (tcs[0].type, tcs[0].hi, tcs[0].lo) if tcs else None


def same_positions(a, b):
    return len(a) == len(b) and all(
        (math.isnan(x) and math.isnan(y)) or abs(x - y) <= 1e-3 for x, y in zip(a, b))
