// OSC 1.0 messages, encoded in the page: the daemon takes a page's controls exactly as its
// control socket takes them (same decoder, same range checks, same secret rule).

const enc = new TextEncoder();

function padded(bytes) {
  const out = new Uint8Array(Math.ceil((bytes.length + 1) / 4) * 4);
  out.set(bytes);
  return out;
}

/**
 * Encodes one message. `args`: [type, value] pairs, type "s" (string), "f" (float32) or
 * "i" (int32).
 */
export function encodeMessage(address, args) {
  const parts = [padded(enc.encode(address)), padded(enc.encode("," + args.map((a) => a[0]).join("")))];
  for (const [type, value] of args) {
    if (type === "s") {
      parts.push(padded(enc.encode(String(value))));
    } else {
      const b = new Uint8Array(4);
      const dv = new DataView(b.buffer);
      if (type === "f") dv.setFloat32(0, value, false);
      else dv.setInt32(0, value, false);
      parts.push(b);
    }
  }
  const out = new Uint8Array(parts.reduce((s, p) => s + p.length, 0));
  let at = 0;
  for (const p of parts) { out.set(p, at); at += p.length; }
  return out.buffer;
}
