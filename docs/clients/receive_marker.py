#!/usr/bin/env python3
"""Subscribe to a running `emoshift serve` and print one marker of the edited stream.

    pip install python-osc
    python3 receive_marker.py --daemon 127.0.0.1:9001 --port 9100 --marker 0

It sends `/subscribe <port> compact` to the daemon's control address (the daemon only ever
sends to the address a subscription came from), then decodes the compact profile: a bundle of
`/mocap/frame ,ihbb` (frame number, capture time in microseconds, missing-marker bitmask,
big-endian float32 positions x y z per marker in mm) and `/emoshift/state ,sf` (target emotion,
current amount).
"""
import argparse
import struct

from pythonosc import dispatcher, osc_server
from pythonosc.osc_message_builder import OscMessageBuilder


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--daemon", default="127.0.0.1:9001", help="daemon control HOST:PORT")
    ap.add_argument("--port", type=int, default=9100, help="local port to receive on")
    ap.add_argument("--marker", type=int, default=0, help="marker index to print")
    ap.add_argument("--frames", type=int, default=0, help="stop after this many frames (0: never)")
    args = ap.parse_args()

    host, port = args.daemon.rsplit(":", 1)
    state = {"target": "", "amount": 0.0, "seen": 0}

    def on_frame(_addr, frame, time_us, mask, positions):
        i = args.marker
        missing = bool(mask[i // 8] >> (i % 8) & 1) if i // 8 < len(mask) else True
        x, y, z = struct.unpack_from(">3f", positions, 12 * i)
        where = "missing" if missing else f"{x:8.2f} {y:8.2f} {z:8.2f} mm"
        print(f"frame {frame:6d}  t {time_us / 1e6:8.3f} s  marker {i}: {where}  "
              f"[{state['target']} {state['amount']:.2f}]")
        state["seen"] += 1
        if args.frames and state["seen"] >= args.frames:
            raise KeyboardInterrupt

    def on_state(_addr, target, amount):
        state["target"], state["amount"] = target, amount

    d = dispatcher.Dispatcher()
    d.map("/mocap/frame", on_frame)
    d.map("/emoshift/state", on_state)
    server = osc_server.BlockingOSCUDPServer(("127.0.0.1", args.port), d)
    # Subscribe from the receiving socket so the daemon answers to this very address.
    msg = OscMessageBuilder(address="/subscribe")
    msg.add_arg(args.port, "i")
    msg.add_arg("compact", "s")
    server.socket.sendto(msg.build().dgram, (host, int(port)))
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
