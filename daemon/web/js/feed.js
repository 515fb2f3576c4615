// Decodes the daemon's snapshot messages (layout in daemon/src/serve/monitor/wire.rs).

const MAGIC = 0x454d4631; // "EMF1"
const text = new TextDecoder();

/** A snapshot from its binary message, or null when it is not one. */
export function decodeSnapshot(buf) {
  if (buf.byteLength < 64) return null;
  const dv = new DataView(buf);
  if (dv.getUint32(0, false) !== MAGIC) return null;
  const n = dv.getUint32(12, true);
  const m = dv.getUint32(16, true);
  const tlen = dv.getUint32(60, true);
  let at = 64 + Math.ceil(tlen / 4) * 4;
  if (buf.byteLength < at + 4 * (6 * n + 2 * m) + n) return null;
  // Copies, so a snapshot kept for the strip chart does not pin the whole message.
  const floats = (len) => {
    const out = new Float32Array(len);
    for (let k = 0; k < len; k++) out[k] = dv.getFloat32(at + 4 * k, true);
    at += 4 * len;
    return out;
  };
  const snap = {
    stream: dv.getInt32(4, true),
    frame: dv.getInt32(8, true),
    n, m,
    amount: dv.getFloat32(20, true),
    amountGoal: dv.getFloat32(24, true),
    ramp: dv.getFloat32(28, true),
    bypass: (dv.getUint32(32, true) & 1) === 1,
    frames: dv.getFloat64(36, true),
    duplicates: dv.getFloat64(44, true),
    stale: dv.getFloat64(52, true),
    target: text.decode(new Uint8Array(buf, 64, tlen)),
  };
  snap.input = floats(3 * n);
  snap.output = floats(3 * n);
  snap.uIn = floats(m);
  snap.uOut = floats(m);
  snap.flags = new Uint8Array(buf.slice(at, at + n));
  return snap;
}

export const FLAG_MISSING = 1;
export const FLAG_FILLED = 2;
