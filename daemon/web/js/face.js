// The face in two views (front and side) with a rotate control: the markers as received
// (rings) and as edited (dots), the edit as a line between them, missing and filled markers
// marked, and the marker under the pointer named.

import { FLAG_MISSING, FLAG_FILLED } from "./feed.js";
import { fit } from "./canvas.js";

const COLORS = { input: "#7fb2ff", edited: "#f2a33a", miss: "#ff5d5d", fill: "#d77cff", grid: "#1d2530" };
const AXES = { x: [1, 0, 0], y: [0, 1, 0], z: [0, 0, 1] };

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

/** The face's frame from one snapshot: up, front and right axes, centre and size. */
function frameOf(snap, upChoice) {
  const n = snap.n;
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  const sum = [0, 0, 0];
  for (let i = 0; i < n; i++) {
    for (let c = 0; c < 3; c++) {
      const v = snap.output[3 * i + c];
      lo[c] = Math.min(lo[c], v);
      hi[c] = Math.max(hi[c], v);
      sum[c] += v;
    }
  }
  const mean = sum.map((s) => s / Math.max(n, 1));
  const median = [0, 1, 2].map((c) => {
    const v = Array.from({ length: n }, (_, i) => snap.output[3 * i + c]).sort((a, b) => a - b);
    return v[Math.floor(n / 2)] ?? 0;
  });
  const range = [0, 1, 2].map((c) => hi[c] - lo[c]);
  // A face is shallower than it is wide or tall, and taller than wide.
  const byRange = [0, 1, 2].sort((a, b) => range[a] - range[b]);
  const depth = byRange[0];
  const up = upChoice !== "auto" ? "xyz".indexOf(upChoice) : byRange[2];
  const d = up === depth ? byRange[1] : depth;
  // A face curves away from the viewer: most markers lie near its front, the cheeks' edges
  // and a head band trail far behind. The front is the side nearer the median.
  const sign = hi[d] - median[d] <= median[d] - lo[d] ? 1 : -1;
  const U = AXES["xyz"[up]];
  const F = AXES["xyz"[d]].map((v) => v * sign);
  const R = cross(U, F);
  let radius = 1;
  let upExt = 1;
  for (let i = 0; i < n; i++) {
    const p = [0, 1, 2].map((c) => snap.output[3 * i + c] - mean[c]);
    radius = Math.max(radius, Math.hypot(dot(p, R), dot(p, F)));
    upExt = Math.max(upExt, Math.abs(dot(p, U)));
  }
  return { U, F, R, mean, radius, upExt };
}

/** Adds a circle of radius `r` around each point to the current path (one draw call for all). */
function circles(g, points, r) {
  g.beginPath();
  for (const p of points) {
    if (!p) continue;
    g.moveTo(p[0] + r, p[1]);
    g.arc(p[0], p[1], r, 0, 2 * Math.PI);
  }
}

/** The edit as lines, the input as rings, the output as dots, gaps ringed: a few paths. */
function drawMarkers(g, snap, pin, pout, k) {
  g.strokeStyle = "rgba(242,163,58,.55)";
  g.beginPath();
  pin.forEach((p, i) => {
    if (p) { g.moveTo(p[0], p[1]); g.lineTo(pout[i][0], pout[i][1]); }
  });
  g.stroke();
  g.lineWidth = 1.5 * k;
  g.strokeStyle = COLORS.input;
  circles(g, pin, 4 * k);
  g.stroke();
  g.fillStyle = COLORS.edited;
  circles(g, pout, 2.6 * k);
  g.fill();
  g.lineWidth = 1.8;
  for (const [flag, color] of [[FLAG_MISSING, COLORS.miss], [FLAG_FILLED, COLORS.fill]]) {
    // A missing marker is also filled: ring it once, red.
    const ringed = pout.map((p, i) => {
      const f = snap.flags[i];
      const show = flag === FLAG_MISSING ? f & FLAG_MISSING : (f & FLAG_FILLED) && !(f & FLAG_MISSING);
      return show ? p : null;
    });
    g.strokeStyle = color;
    circles(g, ringed, 6.5 * k);
    g.stroke();
  }
}

export function createFace(els, redraw) {
  let yaw = 0;
  let stream = null;
  let hoverAt = null; // { view, x, y, index }
  let textAt = 0;
  const views = [
    { canvas: els.front, turn: 0, points: [] },
    { canvas: els.side, turn: Math.PI / 2, points: [] },
  ];

  function setYaw(deg) {
    yaw = ((((deg + 180) % 360) + 360) % 360) - 180;
    els.yaw.value = String(Math.round(yaw));
    els.yawValue.textContent = `${Math.round(yaw)}°`;
    redraw();
  }
  els.yaw.addEventListener("input", () => setYaw(Number(els.yaw.value)));
  els.reset.addEventListener("click", () => { if (stream) stream.frame = null; setYaw(0); });
  els.upAxis.addEventListener("change", () => { if (stream) stream.frame = null; redraw(); });

  for (const v of views) {
    let drag = null;
    v.canvas.addEventListener("pointerdown", (e) => { drag = e.clientX; v.canvas.setPointerCapture(e.pointerId); });
    v.canvas.addEventListener("pointerup", () => { drag = null; });
    v.canvas.addEventListener("pointermove", (e) => {
      if (drag !== null && e.buttons) {
        setYaw(yaw + (e.clientX - drag) * 0.6);
        drag = e.clientX;
      }
      const r = v.canvas.getBoundingClientRect();
      hoverAt = { view: v, x: e.clientX - r.left, y: e.clientY - r.top };
      showHover();
    });
    v.canvas.addEventListener("pointerleave", () => { hoverAt = null; els.hover.hidden = true; });
  }

  function project(frame, p, turn, scale, cx, cy) {
    const d = [p[0] - frame.mean[0], p[1] - frame.mean[1], p[2] - frame.mean[2]];
    const a = (yaw * Math.PI) / 180 + turn;
    const r = dot(d, frame.R);
    const f = dot(d, frame.F);
    return [cx + scale * (r * Math.cos(a) + f * Math.sin(a)), cy - scale * dot(d, frame.U)];
  }

  function drawView(v, s) {
    const { g, w, h } = fit(v.canvas);
    const snap = s.snap;
    const scale = Math.min(w / (2.3 * s.frame.radius), h / (2.5 * s.frame.upExt));
    const [cx, cy] = [w / 2, h / 2];
    // Markers shrink with the view, so a phone's small views stay readable.
    const k = Math.max(0.45, Math.min(1, w / 360));
    g.strokeStyle = COLORS.grid;
    g.lineWidth = 1;
    g.beginPath();
    g.moveTo(cx, 12); g.lineTo(cx, h - 12);
    g.moveTo(12, cy); g.lineTo(w - 12, cy);
    g.stroke();
    const at = (buf, i) => project(s.frame, buf.subarray(3 * i, 3 * i + 3), v.turn, scale, cx, cy);
    const pout = [];
    const pin = [];
    for (let i = 0; i < snap.n; i++) {
      pout.push(at(snap.output, i));
      pin.push(snap.flags[i] & FLAG_MISSING ? null : at(snap.input, i));
    }
    drawMarkers(g, snap, pin, pout, k);
    // Kept for the pointer (and on the canvas element for scripts/browser-check).
    v.points = pout;
    v.canvas.markerPoints = pout;
    if (hoverAt && hoverAt.view === v && hoverAt.index !== undefined) {
      g.strokeStyle = "#ffffff";
      g.lineWidth = 1.5;
      circles(g, [pout[hoverAt.index]], 8.5);
      g.stroke();
    }
  }

  function showHover() {
    const s = stream;
    if (!hoverAt || !s || !s.snap) return;
    const { view, x, y } = hoverAt;
    let best = -1;
    let bestD = 14;
    view.points.forEach((p, i) => {
      const d = Math.hypot(p[0] - x, p[1] - y);
      if (d < bestD) { bestD = d; best = i; }
    });
    if (best < 0) { els.hover.hidden = true; hoverAt.index = undefined; return; }
    hoverAt.index = best;
    const snap = s.snap;
    const label = s.model && s.model.labels ? s.model.labels[best] : `marker ${best}`;
    const f = snap.flags[best];
    const stateText = f & FLAG_MISSING ? "missing · filled by the model" : f & FLAG_FILLED ? "rejected glitch · filled" : "tracked";
    let moved = "";
    if (!(f & FLAG_MISSING)) {
      const d = [0, 1, 2].map((c) => snap.output[3 * best + c] - snap.input[3 * best + c]);
      moved = ` · edit ${Math.hypot(...d).toFixed(2)} mm`;
    }
    els.hover.innerHTML = "";
    const b = document.createElement("b");
    b.textContent = label;
    els.hover.append(b, ` ${stateText}${moved}`);
    const box = view.canvas.getBoundingClientRect();
    const parent = els.hover.parentElement.getBoundingClientRect();
    els.hover.style.left = `${box.left - parent.left + x + 14}px`;
    els.hover.style.top = `${box.top - parent.top + y + 10}px`;
    els.hover.hidden = false;
  }

  return {
    setStream(s) {
      stream = s;
      els.title.textContent = s ? s.name : "";
    },
    draw(s) {
      stream = s;
      if (!s.frame || s.frame.n !== s.snap.n) {
        s.frame = frameOf(s.snap, els.upAxis.value);
        s.frame.n = s.snap.n;
      }
      for (const v of views) drawView(v, s);
      // Only a change is written: any text written invalidates the page's layout.
      if (els.title.textContent !== s.name) els.title.textContent = s.name;
      // Text relayouts the page: four times a second is enough to read it.
      const now = performance.now();
      if (now - textAt >= 250) {
        textAt = now;
        const missing = s.snap.flags.reduce((a, f) => a + (f & FLAG_MISSING ? 1 : 0), 0);
        els.frameNo.textContent = `frame ${s.snap.frame} · ${s.snap.n} markers · ${missing} missing`;
      }
      if (hoverAt) showHover();
    },
  };
}
