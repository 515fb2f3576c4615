// The performer's page: the prompt, read from /session.json four times a second, and big
// buttons that post the OSC message the session's control socket takes (encoded by serve's
// osc.js), so the page, the keyboard and OSC go through the same session and the same rules.
// The buttons shown follow the state the session reports; a refused press shows why.

import { encodeMessage } from "./osc.js";

const $ = (id) => document.getElementById(id);
const setText = (el, text) => { if (el.textContent !== text) el.textContent = text; };

/** The buttons that make sense in each state (the session checks again: it decides). */
function shown(v) {
  if (v.finishing) return [];
  if (v.offered.length) return ["redo", "finish"];
  switch (v.state) {
    case "waiting": return ["start", "skip", "back", ...(v.accepted ? ["retake", "finish"] : [])];
    case "recording": return ["stop"];
    case "review": return ["retake", "skip", "back"];
    case "done": return ["finish", "retake", "back"];
    default: return [];
  }
}

let control = { allowed: false, why: "connecting", secret: false };
let last = null;

function say(text, bad) {
  const why = $("why");
  setText(why, text);
  why.className = bad ? "bad" : "";
}

async function press(address) {
  const secret = $("secret").value;
  const args = control.secret && secret ? [["s", secret]] : [];
  try {
    const r = await fetch("/control", { method: "POST", body: encodeMessage(address, args),
                                        headers: { "Content-Type": "application/octet-stream" } });
    const answer = await r.json();
    if (answer.ok) say("", false);
    else say(`refused: ${answer.error}`, true);
  } catch (e) {
    say("the session did not answer: is it still running?", true);
  }
  tick();
}

function render(v) {
  $("light").className = v.state === "recording" ? "on" : "";
  setText($("state"), v.finishing ? "training" : v.state);
  setText($("count"), `take ${v.take} of ${v.takes} · sentence ${v.sentence}`);
  setText($("markers"), `markers ${v.markers_seen} / ${v.markers}`);
  const done = v.state === "done" && !v.offered.length;
  setText($("emotion"), v.finishing ? "training" : done ? "done" : v.emotion);
  setText($("text"), v.finishing ? "Training and analysing the takes…"
    : v.offered.length ? `${v.offered.length} take${v.offered.length > 1 ? "s" : ""} to re-record`
    : done ? "Thank you." : v.text);
  setText($("refused"), v.refused ? `take refused: ${v.refused}` : "");
  const advice = $("advice");
  if (advice.dataset.text !== v.advice.join("\n")) {
    advice.dataset.text = v.advice.join("\n");
    advice.replaceChildren(...v.advice.map((line) => {
      const li = document.createElement("li");
      li.textContent = line;
      return li;
    }));
  }
  setText($("redo"), `Re-record ${v.offered.length}`);
  setText($("finish"), v.offered.length ? "Keep this model" : "Finish");
  setText($("retake"), v.state === "review" ? "Retake" : "Retake last");
  const show = shown(v);
  for (const b of document.querySelectorAll("#controls button")) {
    b.hidden = !show.includes(b.id);
    b.disabled = !control.allowed;
  }
  $("secret-row").hidden = !control.secret;
  if (!control.allowed && control.why) say(`view only: ${control.why}`, true);
}

async function tick() {
  try {
    const r = await fetch("/session.json", { cache: "no-store" });
    const v = await r.json();
    control = v.control;
    last = v;
    render(v);
  } catch (e) {
    setText($("state"), "session gone");
    for (const b of document.querySelectorAll("#controls button")) b.disabled = true;
  }
}

for (const b of document.querySelectorAll("#controls button")) {
  b.addEventListener("click", () => press(b.dataset.control));
}
window.emoshiftSession = { last: () => last };
setInterval(tick, 250);
tick();
