#!/usr/bin/env python3
"""Builds protocol/tests/fixtures/natnet/ from ../shared/data/natnet (run from the repo root).

    python3 scripts/natnet_fixtures.py [SHARED_NATNET_DIR]

Outputs (all small; see protocol/tests/fixtures/natnet/SOURCE.txt):
  traffic.udp.gz      every UDP payload of motive-2.1/raw/traffic.pcapng, in capture order, as
                      records: u64 LE capture time in microseconds, u16 LE source port, u16 LE
                      destination port, u16 LE payload length, then the payload. No IP addresses.
  sampleclient.txt.gz what SampleClient printed per frame, one line per frame, fields separated by
                      " | " (see FORMAT below). Values are the printed strings, unchanged.
  *.bin               the single packets of motive-2.1/, copied as they are.

Only the Python standard library: pcapng and Ethernet/IPv4/UDP are parsed by hand, and the
script refuses anything it does not understand (fragments, other link types) rather than guess.
"""

import gzip
import os
import re
import shutil
import struct
import sys

FORMAT = (
    "frame_id | timestamp | software_ms | system_ms | timecode | "
    "other: x,y,z;... | rigid: id,error,valid,x,y,z,qx,qy,qz,qw;... | "
    "labeled: model,marker,occluded,pcsolved,modelsolved,size,x,y,z;..."
)


def pcapng_packets(path):
    """Yields (timestamp_us, frame bytes) of every Enhanced Packet Block."""
    data = open(path, "rb").read()
    off, endian, tsresol = 0, "<", 1_000_000
    while off < len(data):
        btype, blen = struct.unpack_from(endian + "II", data, off)
        if btype == 0x0A0D0D0A:
            bom = struct.unpack_from("<I", data, off + 8)[0]
            endian = "<" if bom == 0x1A2B3C4D else ">"
            btype, blen = struct.unpack_from(endian + "II", data, off)
        body = data[off + 8 : off + blen - 4]
        if btype == 1:
            (linktype,) = struct.unpack_from(endian + "H", body, 0)
            if linktype != 1:
                raise SystemExit(f"unsupported link type {linktype}")
        elif btype == 6:
            _iface, th, tl, caplen, origlen = struct.unpack_from(endian + "IIIII", body, 0)
            if caplen != origlen:
                raise SystemExit("truncated capture")
            yield ((th << 32) | tl) * 1_000_000 // tsresol, body[20 : 20 + caplen]
        off += blen


def udp_payload(frame):
    """(src port, dst port, payload) of an Ethernet/IPv4/UDP frame, or None for anything else."""
    (ethertype,) = struct.unpack_from("!H", frame, 12)
    if ethertype != 0x0800:
        return None
    ip = frame[14:]
    ihl = (ip[0] & 0x0F) * 4
    total_len, frag = struct.unpack_from("!H2xH", ip, 2)
    if ip[9] != 17:
        return None
    if frag & 0x3FFF:
        raise SystemExit("ip fragment: not handled")
    udp = ip[ihl:total_len]
    sport, dport, ulen = struct.unpack_from("!HHH", udp, 0)
    return sport, dport, udp[8:ulen]


def write_traffic(pcap, out):
    records, n = bytearray(), 0
    for ts_us, frame in pcapng_packets(pcap):
        p = udp_payload(frame)
        if p is None:
            continue
        sport, dport, payload = p
        records += struct.pack("<QHHH", ts_us, sport, dport, len(payload)) + payload
        n += 1
    with gzip.GzipFile(out, "wb", mtime=0) as f:
        f.write(records)
    return n


NUM = r"(-?[0-9.]+)"


def parse_sampleclient(path):
    """One dict per 'FrameID' block; lines from other threads interleave and are ignored."""
    frames, cur = [], None
    for line in open(path, encoding="utf-8", errors="replace"):
        line = line.rstrip("\n")
        if m := re.match(r"FrameID : (\d+)$", line):
            cur = {"id": m[1], "other": [], "rigid": [], "labeled": [], "pending_rb": None}
            frames.append(cur)
        elif cur is None:
            continue
        elif m := re.match(r"Timestamp : " + NUM + "$", line):
            cur["ts"] = m[1]
        elif m := re.match(r"Software latency : " + NUM + " milliseconds$", line):
            cur["sw"] = m[1]
        elif m := re.match(r"System latency : " + NUM + " milliseconds$", line):
            cur["sys"] = m[1]
        elif m := re.match(r"Timecode : (\S+)$", line):
            cur["tc"] = m[1]
        elif m := re.match(r"Other Marker \d+ : " + NUM + r"\t" + NUM + r"\t" + NUM + "$", line):
            cur["other"].append(",".join(m.groups()))
        elif m := re.match(r"Rigid Body \[ID=(\d+)  Error=" + NUM + r"  Valid=(\d)\]$", line):
            cur["pending_rb"] = list(m.groups())
        elif re.match(r"\t" + r"\t".join([NUM] * 7) + "$", line) and cur["pending_rb"]:
            vals = re.findall(NUM, line)
            cur["rigid"].append(",".join(cur["pending_rb"] + vals))
            cur["pending_rb"] = None
        elif m := re.match(
            r"Labeled Marker \[ModelID=(\d+), MarkerID=(\d+), Occluded=(\d), PCSolved=(\d), "
            r"ModelSolved=(\d)\] \[size=" + NUM + r"\] \[pos=" + NUM + "," + NUM + "," + NUM + r"\]$",
            line,
        ):
            cur["labeled"].append(",".join(m.groups()))
    return frames


def write_sampleclient(path, out):
    frames = parse_sampleclient(path)
    lines = [f"# {FORMAT}"]
    for f in frames:
        lines.append(
            " | ".join(
                [f["id"], f["ts"], f["sw"], f["sys"], f["tc"], ";".join(f["other"]),
                 ";".join(f["rigid"]), ";".join(f["labeled"])]
            )
        )
    with gzip.GzipFile(out, "wb", mtime=0) as fh:
        fh.write(("\n".join(lines) + "\n").encode())
    return len(frames)


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else "../shared/data/natnet"
    dst = "protocol/tests/fixtures/natnet"
    os.makedirs(dst, exist_ok=True)
    n = write_traffic(os.path.join(src, "motive-2.1/raw/traffic.pcapng"),
                      os.path.join(dst, "traffic.udp.gz"))
    f = write_sampleclient(os.path.join(src, "motive-2.1/raw/SampleClient_output.txt"),
                           os.path.join(dst, "sampleclient.txt.gz"))
    for name in sorted(os.listdir(os.path.join(src, "motive-2.1"))):
        if name.endswith(".bin"):
            shutil.copyfile(os.path.join(src, "motive-2.1", name), os.path.join(dst, name))
    shutil.copyfile(os.path.join(src, "LICENSE.python_natnet"),
                    os.path.join(dst, "LICENSE.python_natnet"))
    print(f"{n} udp datagrams, {f} SampleClient frames -> {dst}")


if __name__ == "__main__":
    main()
