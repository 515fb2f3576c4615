// The monitor page: one WebSocket to the daemon; snapshots (binary) and health, models and
// replies (JSON) in; controls (OSC messages) out. Draws only when something new arrived.

import { decodeSnapshot } from "./feed.js";
import { createFace } from "./face.js";
import { createStrip, HISTORY_S } from "./strip.js";
import { createControl } from "./control.js";
import { createHealth } from "./health.js";

const $ = (id) => document.getElementById(id);

// Everything the page knows; also read by scripts/browser-check.
const state = {
  hello: null,
  streams: new Map(), // id -> { id, name, model, snap, history, level }
  selected: null,
  emotions: null,
  status: null,
  received: 0,
  drawn: 0,
  replies: [],
  connected: false,
};
window.emoshift = state;

let ws = null;
let lastHealth = 0;
let backoff = 500;
let pending = false;

const face = createFace({
  front: $("front"), side: $("side"), hover: $("hover"), yaw: $("yaw"), yawValue: $("yaw-value"),
  upAxis: $("up-axis"), reset: $("face-reset"), title: $("face-title"), frameNo: $("frame-no"),
}, () => schedule());
const strip = createStrip($("strip"));
const control = createControl(send);
const health = createHealth(control.sendControl);

function selectedStream() {
  return state.selected === null ? null : state.streams.get(state.selected) || null;
}

function stream(id) {
  let s = state.streams.get(id);
  if (!s) {
    s = { id, name: `stream ${id}`, model: null, snap: null, history: [], level: null, seenAt: 0 };
    state.streams.set(id, s);
    if (state.selected === null) select(id);
    renderTabs();
  }
  return s;
}

function select(id) {
  state.selected = id;
  renderTabs();
  face.setStream(selectedStream());
  schedule();
}

function renderTabs() {
  const nav = $("streams");
  if (state.streams.size === 0) {
    nav.innerHTML = '<span class="dim">waiting for frames…</span>';
    return;
  }
  nav.replaceChildren(...[...state.streams.values()].map((s) => {
    const b = document.createElement("button");
    b.type = "button";
    b.className = "tab" + (s.id === state.selected ? " sel" : "");
    b.dataset.stream = s.id;
    b.innerHTML = '<span class="dot"></span>';
    b.append(s.name);
    b.addEventListener("click", () => select(s.id));
    return b;
  }));
}

function onSnapshot(snap) {
  const s = stream(snap.stream);
  s.snap = snap;
  s.seenAt = performance.now();
  state.received++;
  s.history.push({ t: s.seenAt, uIn: snap.uIn, uOut: snap.uOut });
  while (s.history.length && s.seenAt - s.history[0].t > HISTORY_S * 1000) s.history.shift();
  control.track(s, snap);
  if (s.id === state.selected) schedule();
}

function onText(msg) {
  switch (msg.type) {
    case "hello":
      state.hello = msg;
      control.setHello(msg);
      break;
    case "model": {
      const s = stream(msg.stream);
      s.model = msg;
      if (s.id === state.selected) face.setStream(s);
      health.setModel(selectedStream());
      break;
    }
    case "emotions":
      state.emotions = msg.emotion;
      control.setEmotions(msg.emotion);
      break;
    case "status":
      state.status = msg;
      for (const st of msg.streams) {
        const s = stream(st.id);
        if (s.name !== st.name) { s.name = st.name; renderTabs(); }
      }
      for (const id of [...state.streams.keys()]) {
        if (!msg.streams.some((st) => st.id === id)) {
          state.streams.delete(id);
          if (state.selected === id) state.selected = state.streams.size ? state.streams.keys().next().value : null;
          renderTabs();
        }
      }
      // Tables at most twice a second: they relayout the panel.
      if (performance.now() - lastHealth >= 450) {
        lastHealth = performance.now();
        health.update(msg, selectedStream());
      }
      break;
    case "reply":
      state.replies.push(msg);
      if (state.replies.length > 50) state.replies.shift();
      control.onReply(msg);
      break;
  }
}

function schedule() {
  if (pending) return;
  pending = true;
  requestAnimationFrame(draw);
}

let frames = 0;
let since = performance.now();
let lastSlow = 0;
function draw() {
  pending = false;
  const s = selectedStream();
  if (!s || !s.snap) return;
  face.draw(s);
  // The strip scrolls 10 s across the panel and the map moves on a 1 s low-pass: ten
  // redraws a second show them as well as thirty, for a third of the page's drawing.
  const slow = performance.now();
  if (slow - lastSlow >= 100) {
    lastSlow = slow;
    strip.draw(s);
    control.draw(s);
  }
  state.drawn++;
  frames++;
  const now = performance.now();
  if (now - since >= 1000) {
    const rate = `${Math.round((frames * 1000) / (now - since))} fps`;
    if ($("rate").textContent !== rate) $("rate").textContent = rate;
    frames = 0;
    since = now;
  }
}

function send(buffer) {
  if (ws && ws.readyState === WebSocket.OPEN) {
    ws.send(buffer);
    return true;
  }
  control.onReply({ ok: false, address: "", error: "not connected to the daemon" });
  return false;
}

function setLink(text, cls) {
  const el = $("link");
  el.textContent = text;
  el.className = "pill " + cls;
}

function connect() {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  ws = new WebSocket(`${scheme}://${location.host}/ws`);
  ws.binaryType = "arraybuffer";
  ws.onopen = () => { backoff = 500; state.connected = true; setLink("live", "on"); };
  ws.onmessage = (e) => {
    if (typeof e.data === "string") onText(JSON.parse(e.data));
    else {
      const snap = decodeSnapshot(e.data);
      if (snap) onSnapshot(snap);
    }
  };
  ws.onclose = () => {
    state.connected = false;
    setLink("reconnecting", "bad");
    setTimeout(connect, backoff);
    backoff = Math.min(backoff * 2, 2000);
  };
}

// Streams that stop sending show it on their tab.
setInterval(() => {
  const now = performance.now();
  for (const b of document.querySelectorAll(".tab")) {
    const s = state.streams.get(Number(b.dataset.stream));
    b.classList.toggle("stale", !s || now - s.seenAt > 1000);
  }
}, 500);

window.addEventListener("resize", () => schedule());
connect();
