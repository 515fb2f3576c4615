#!/usr/bin/env python3
"""Subscribe to a running `emoshift serve` and print one marker of the edited stream.

    pip install python-osc
    python3 receive_marker.py --daemon 127.0.0.1:9001 --port 9100 --marker 0
    # from another PC (the daemon's control_allow must admit it, see docs/osc.md):
    python3 receive_marker.py --daemon 192.168.1.20:9001 --port 9100 --marker 0

It sends `/subscribe <port> compact` to the daemon's control address (the daemon only ever
sends to the address a subscription came from), then decodes the compact profile: a bundle of
`/mocap/frame ,ihbb` (frame number, capture time in microseconds, missing-marker bitmask,
big-endian float32 positions x y z per marker in mm) and `/emoshift/state ,sf` (target emotion,
current amount).

A subscription is a lease (`subscription_lease_s`, 10 s by default): the client sends the same
`/subscribe` again every `--renew` seconds, or the daemon stops sending. From another host the
daemon first answers `/subscribe/challenge ,i cookie`; the client echoes the cookie as the last
argument of the same `/subscribe` (`,isi`) and keeps it for the renewals. A daemon that restarted
or a cookie that aged out is answered again with a new challenge, which is echoed the same way.
"""
import argparse
import struct
import threading
import time

from pythonosc import dispatcher, osc_server
from pythonosc.osc_message_builder import OscMessageBuilder


def subscribe_message(port, profile, cookie):
    msg = OscMessageBuilder(address="/subscribe")
    msg.add_arg(port, "i")
    msg.add_arg(profile, "s")
    if cookie is not None:
        msg.add_arg(cookie, "i")
    return msg.build().dgram


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--daemon", default="127.0.0.1:9001", help="daemon control HOST:PORT")
    ap.add_argument("--bind", default="0.0.0.0",
                    help="local address to receive on (0.0.0.0: every interface, so a daemon on "
                         "another PC reaches it)")
    ap.add_argument("--port", type=int, default=9100, help="local port to receive on")
    ap.add_argument("--marker", type=int, default=0, help="marker index to print")
    ap.add_argument("--frames", type=int, default=0, help="stop after this many frames (0: never)")
    ap.add_argument("--seconds", type=float, default=0, help="stop after this long (0: never)")
    ap.add_argument("--renew", type=float, default=3.0,
                    help="seconds between lease renewals (well under the daemon's "
                         "subscription_lease_s, 10 s by default)")
    args = ap.parse_args()

    host, port = args.daemon.rsplit(":", 1)
    daemon = (host, int(port))
    state = {"target": "", "amount": 0.0, "seen": 0, "cookie": None}
    done = threading.Event()

    def on_frame(_addr, frame, time_us, mask, positions):
        i = args.marker
        missing = bool(mask[i // 8] >> (i % 8) & 1) if i // 8 < len(mask) else True
        where = "missing"
        if not missing and len(positions) >= 12 * (i + 1):
            x, y, z = struct.unpack_from(">3f", positions, 12 * i)
            where = f"{x:8.2f} {y:8.2f} {z:8.2f} mm"
        print(f"frame {frame:6d}  t {time_us / 1e6:8.3f} s  marker {i}: {where}  "
              f"[{state['target']} {state['amount']:.2f}]", flush=True)
        state["seen"] += 1
        if args.frames and state["seen"] >= args.frames:
            done.set()

    def on_state(_addr, target, amount):
        state["target"], state["amount"] = target, amount

    def subscribe():
        # From the receiving socket, so the daemon answers to this very address.
        dgram = subscribe_message(args.port, "compact", state["cookie"])
        server.socket.sendto(dgram, daemon)

    def on_challenge(_addr, cookie):
        print(f"subscription challenged by the daemon: echoing cookie {cookie}", flush=True)
        state["cookie"] = cookie
        subscribe()

    def on_error(_addr, *why):
        print("daemon error:", *why, flush=True)

    d = dispatcher.Dispatcher()
    d.map("/mocap/frame", on_frame)
    d.map("/emoshift/state", on_state)
    d.map("/subscribe/challenge", on_challenge)
    d.map("/emoshift/error", on_error)
    server = osc_server.ThreadingOSCUDPServer((args.bind, args.port), d)
    threading.Thread(target=server.serve_forever, daemon=True).start()

    started = time.monotonic()
    try:
        while not done.is_set():
            subscribe()
            left = args.renew
            if args.seconds:
                left = min(left, args.seconds - (time.monotonic() - started))
                if left <= 0:
                    break
            done.wait(left)
    except KeyboardInterrupt:
        pass
    server.shutdown()
    server.server_close()


if __name__ == "__main__":
    main()
