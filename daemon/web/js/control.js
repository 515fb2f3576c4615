// Emotion control: the named emotions as buttons, the level map, amount, ramp and bypass,
// and the state as the daemon reports it in every snapshot (never as the page assumes).
// Every control goes out as the OSC message the control socket takes.

import { encodeMessage } from "./osc.js";
import { fit } from "./canvas.js";

const $ = (id) => document.getElementById(id);
const READ_ONLY = new Set(["/status", "/emotion/list"]);
/** Writes text only when it changed: each write can relayout the page. */
const setText = (el, text) => { if (el.textContent !== text) el.textContent = text; };
/** Seconds of the page's own low-pass of the emotion levels drawn on the map. */
const LEVEL_S = 1.0;

export function createControl(send) {
  let points = [];
  let hello = null;
  let draggingUntil = 0;
  let lastAmountSent = 0;
  const amount = $("amount");
  const amountOut = $("amount-out");
  const map = $("levelmap");
  const reply = $("reply");

  function sendControl(address, args = []) {
    const secret = $("secret").value;
    const signed = !READ_ONLY.has(address) && hello && hello.control.secret && secret;
    return send(encodeMessage(address, signed ? [...args, ["s", secret]] : args));
  }

  function sendAmount(force) {
    const now = performance.now();
    // While dragging, at most 10 a second; the last value always goes.
    if (!force && now - lastAmountSent < 100) return;
    lastAmountSent = now;
    sendControl("/emotion/amount", [["f", Number(amount.value)]]);
  }
  amount.addEventListener("input", () => {
    draggingUntil = performance.now() + 1500;
    amountOut.textContent = Number(amount.value).toFixed(2);
    sendAmount(false);
  });
  amount.addEventListener("change", () => sendAmount(true));
  $("ramp").addEventListener("change", () => {
    const v = Number($("ramp").value);
    if (Number.isFinite(v) && v >= 0) sendControl("/emotion/ramp", [["f", v]]);
  });
  $("bypass").addEventListener("click", () => {
    const on = $("bypass").getAttribute("aria-pressed") !== "true";
    sendControl("/bypass", [["i", on ? 1 : 0]]);
  });
  map.addEventListener("click", (e) => {
    const r = map.getBoundingClientRect();
    const hit = nearest(e.clientX - r.left, e.clientY - r.top);
    if (hit) sendControl("/emotion/target", [["s", hit.name]]);
  });

  let layout = null;
  function nearest(x, y) {
    if (!layout) return null;
    let best = null;
    let bestD = 24;
    for (const p of points) {
      const [px, py] = layout(p.level);
      const d = Math.hypot(px - x, py - y);
      if (d < bestD) { bestD = d; best = p; }
    }
    return best;
  }

  function renderButtons() {
    const box = $("emotions");
    box.replaceChildren(...points.map((p) => {
      const b = document.createElement("button");
      b.type = "button";
      b.className = "emo-btn";
      b.dataset.emotion = p.name;
      b.textContent = p.name;
      b.addEventListener("click", () => sendControl("/emotion/target", [["s", p.name]]));
      return b;
    }));
    if (!points.length) box.innerHTML = '<span class="dim">the model has no emotion space</span>';
    map.hidden = points.length === 0;
    applyAccess();
  }

  function applyAccess() {
    const allowed = !hello || hello.control.allowed;
    for (const el of document.querySelectorAll(".control-panel button, .control-panel input, #rec-start, #rec-stop")) {
      el.disabled = !allowed;
    }
    const mode = $("control-mode");
    mode.textContent = allowed ? "control" : "view only";
    mode.className = "pill " + (allowed ? "on" : "warn");
    mode.title = allowed ? "Controls go through the daemon's control path" : (hello.control.why || "");
  }

  function drawMap(s) {
    if (!points.length) return;
    const { g, w, h } = fit(map);
    const dims = points[0].level.length;
    const at = (v) => [v[0], dims > 1 ? v[1] : 0];
    const all = points.flatMap((p) => [at(p.level)]);
    if (s && s.level) all.push(at(s.level.in), at(s.level.out));
    const xs = all.map((p) => p[0]);
    const ys = all.map((p) => p[1]);
    const span = (a) => Math.max(Math.max(...a) - Math.min(...a), 1e-6);
    const sx = (w - 60) / span(xs);
    const sy = dims > 1 ? (h - 44) / span(ys) : 0;
    const scale = dims > 1 ? Math.min(sx, sy) : sx;
    const mx = (Math.max(...xs) + Math.min(...xs)) / 2;
    const my = (Math.max(...ys) + Math.min(...ys)) / 2;
    layout = (v) => { const p = at(v); return [w / 2 + (p[0] - mx) * scale, h / 2 - (p[1] - my) * scale]; };
    g.strokeStyle = "#1d2530";
    g.beginPath();
    const [ox, oy] = layout(dims > 1 ? [0, 0] : [0]);
    g.moveTo(0, oy); g.lineTo(w, oy);
    if (dims > 1) { g.moveTo(ox, 0); g.lineTo(ox, h); }
    g.stroke();
    g.font = "12px system-ui, sans-serif";
    g.textAlign = "center";
    const target = s && s.snap ? s.snap.target : "";
    const placed = [];
    for (const p of points) {
      const [x, y] = layout(p.level);
      const rx = Math.max((p.spread[0] || 0) * scale, 5);
      const ry = dims > 1 ? Math.max((p.spread[1] || 0) * scale, 5) : 5;
      const on = p.name === target;
      g.fillStyle = on ? "rgba(55,198,180,.28)" : "rgba(125,135,149,.16)";
      g.strokeStyle = on ? "#37c6b4" : "#3a4452";
      g.beginPath(); g.ellipse(x, y, rx, ry, 0, 0, 2 * Math.PI); g.fill(); g.stroke();
      g.fillStyle = on ? "#bff3ea" : "#aeb6c2";
      // Above the point, or below it when another label is already there.
      const tw = g.measureText(p.name).width;
      let ty = y - Math.max(ry, 5) - 5;
      const clash = (yy) => placed.some((q) => Math.abs(q[0] - x) < (q[2] + tw) / 2 && Math.abs(q[1] - yy) < 13);
      if (clash(ty)) ty = y + Math.max(ry, 5) + 14;
      placed.push([x, ty, tw]);
      g.fillText(p.name, x, ty);
    }
    if (s && s.level) {
      const [ix, iy] = layout(s.level.in);
      const [ex, ey] = layout(s.level.out);
      g.strokeStyle = "rgba(242,163,58,.7)";
      g.beginPath(); g.moveTo(ix, iy); g.lineTo(ex, ey); g.stroke();
      g.strokeStyle = "#7fb2ff"; g.lineWidth = 2;
      g.beginPath(); g.arc(ix, iy, 5, 0, 2 * Math.PI); g.stroke();
      g.fillStyle = "#f2a33a";
      g.beginPath(); g.arc(ex, ey, 5, 0, 2 * Math.PI); g.fill();
      g.lineWidth = 1;
    }
    g.textAlign = "left";
  }

  return {
    sendControl,
    setHello(h) {
      hello = h;
      $("secret-row").hidden = !h.control.secret;
      applyAccess();
    },
    setEmotions(e) {
      points = e.points || [];
      renderButtons();
    },
    /** The stream's emotion levels, low-passed over about a second, in and out. */
    track(s, snap) {
      const comps = s.model ? s.model.emotion.components : [];
      if (!comps.length || comps.some((k) => k >= snap.m)) { s.level = null; return; }
      const now = [comps.map((k) => snap.uIn[k]), comps.map((k) => snap.uOut[k])];
      const a = s.level ? Math.min(1, 1 / (30 * LEVEL_S)) : 1;
      const prev = s.level || { in: now[0], out: now[1] };
      s.level = {
        in: prev.in.map((v, i) => v + a * (now[0][i] - v)),
        out: prev.out.map((v, i) => v + a * (now[1][i] - v)),
      };
    },
    draw(s) {
      const snap = s.snap;
      setText($("st-target"), snap.target || "none");
      setText($("st-amount"), snap.amount === snap.amountGoal
        ? snap.amount.toFixed(2)
        : `${snap.amount.toFixed(2)} → ${snap.amountGoal.toFixed(2)}`);
      setText($("st-ramp"), `${snap.ramp.toFixed(2)} s`);
      setText($("st-bypass"), snap.bypass ? "on" : "off");
      // Only changes are written (ten times a second): each write invalidates the layout.
      $("st-bypass").classList.toggle("warn", snap.bypass);
      const pressed = snap.bypass ? "true" : "false";
      if ($("bypass").getAttribute("aria-pressed") !== pressed) $("bypass").setAttribute("aria-pressed", pressed);
      for (const b of document.querySelectorAll(".emo-btn")) {
        b.classList.toggle("active", b.dataset.emotion === snap.target);
      }
      if (performance.now() > draggingUntil && document.activeElement !== amount) {
        if (amount.value !== String(snap.amountGoal)) amount.value = String(snap.amountGoal);
        setText(amountOut, snap.amountGoal.toFixed(2));
      }
      const ramp = $("ramp");
      if (document.activeElement !== ramp && ramp.value !== snap.ramp.toFixed(2)) ramp.value = snap.ramp.toFixed(2);
      drawMap(s);
    },
    onReply(msg) {
      if (msg.ok && (msg.address === "/emotion/amount")) return;
      reply.className = "reply " + (msg.ok ? "ok" : "err");
      reply.textContent = msg.ok ? `${msg.address} confirmed` : `${msg.address || "control"} refused: ${msg.error}`;
    },
  };
}
