// Health: frames in and out, drops by reason, stage latencies, subscribers and their leases,
// the model (file, markers matched, quality warnings), and the recording with its control.

const $ = (id) => document.getElementById(id);
const fmt = (v) => (v === null || v === undefined ? "—" : Number(v).toLocaleString("en-US"));

// The panel is refreshed twice a second; only what changed is written, so a steady daemon
// costs the browser no layout.
const setText = (el, text) => { if (el.textContent !== text) el.textContent = text; };
const setClass = (el, cls) => { if (el.className !== cls) el.className = cls; };

/** `count` children of `box`, made by `make` when missing, extra ones removed. */
function children(box, count, make) {
  while (box.children.length > count) box.lastElementChild.remove();
  while (box.children.length < count) box.append(make());
  return [...box.children];
}

function cells(row, values) {
  children(row, values.length, () => document.createElement("td")).forEach((td, i) => {
    const [v, cls] = values[i];
    setText(td, v);
    setClass(td, cls || "");
  });
  return row;
}

/** Rows of a table body, one per item of `rows` ([cells, attributes]). */
function rows(body, list) {
  children(body, list.length, () => document.createElement("tr")).forEach((tr, i) => {
    const [values, attrs = {}] = list[i];
    cells(tr, values);
    for (const [k, v] of Object.entries(attrs)) {
      if (k === "className") setClass(tr, v);
      else if (tr.getAttribute(k) !== v) tr.setAttribute(k, v);
    }
  });
}

function kv(box, pairs) {
  children(box, pairs.length, () => {
    const d = document.createElement("div");
    const a = document.createElement("span");
    a.className = "dim";
    d.append(a, document.createElement("span"));
    return d;
  }).forEach((d, i) => {
    const [k, v, hot] = pairs[i];
    const [a, b] = d.children;
    setText(a, k);
    setText(b, v);
    setClass(b, hot ? "hot" : "");
    if (d.dataset.key !== k) d.dataset.key = k;
  });
}

function defaultPath() {
  const d = new Date();
  const p = (n) => String(n).padStart(2, "0");
  return `emoshift-${d.getFullYear()}${p(d.getMonth() + 1)}${p(d.getDate())}-${p(d.getHours())}${p(d.getMinutes())}${p(d.getSeconds())}.c3d`;
}

export function createHealth(sendControl) {
  let status = null;
  $("rec-path").value = defaultPath();
  $("rec-start").addEventListener("click", () => {
    const path = $("rec-path").value.trim();
    if (!path) return;
    const args = [["s", path]];
    if ($("rec-raw").checked) args.push(["s", path.replace(/(\.[^./]+)?$/, (ext) => `-raw${ext || ".c3d"}`)]);
    if ($("rec-overwrite").checked) args.push(["i", 1]);
    sendControl("/record/start", args);
  });
  $("rec-stop").addEventListener("click", () => {
    sendControl("/record/stop");
    $("rec-path").value = defaultPath();
  });

  function setModel(s) {
    if (!status) return;
    const st = s && status.streams.find((x) => x.id === s.id);
    const m = s && s.model;
    kv($("model"), [
      ["file", (m && m.file) || status.model || "—"],
      ["markers matched", st ? `${st.matched_markers} of ${st.model_markers}` : "—", st && st.matched_markers < st.model_markers],
      ["components", m ? String(m.components) : "—"],
      ["emotion space", m ? `${m.emotion.components.length}-d, ${m.emotion.points.length} emotions` : "—"],
      ["rate", m ? `${m.rate_hz} Hz` : "—"],
    ]);
    const warnings = (m && m.warnings) || [];
    children($("warnings"), warnings.length, () => document.createElement("li"))
      .forEach((li, i) => setText(li, warnings[i]));
  }

  // The NatNet server's clients (`--natnet-server`), from its `natnet_server/*` pairs.
  function natnetServer(nn) {
    $("natnet-server").hidden = !nn;
    if (!nn) return;
    const key = (k) => nn[`natnet_server/${k}`];
    const clients = [];
    for (let n = 0; key(`client/${n}/addr`) !== undefined; n++) {
      clients.push([[
        [key(`client/${n}/addr`)], [key(`client/${n}/version`)],
        [`${(key(`client/${n}/lease_ms`) / 1000).toFixed(1)} s`, "n"], [fmt(key(`client/${n}/frames`)), "n"],
      ]]);
    }
    rows($("t-natnet").tBodies[0], clients);
    const mode = key("multicast") ? `multicast ${key("multicast")}` : "unicast";
    const refused = key("not_allowed") + key("malformed") + key("oversized") + key("over_budget");
    setText($("natnet-line"), `${mode} · markersets ${key("markersets") || "none yet"} · ${fmt(key("frames_sent"))} frames sent · ${fmt(key("connects"))} connects · ${fmt(refused)} refused`);
  }

  return {
    setModel,
    update(msg, selected) {
      status = msg;
      setText($("h-in"), fmt(msg.frames_in));
      setText($("h-out"), fmt(msg.frames_out));
      setText($("h-subs"), fmt(msg.subscribers.length));
      const sel = selected && msg.streams.find((st) => st.id === selected.id);
      const drops = sel ? sel.duplicates + sel.stale : 0;
      const el = $("stream-drops");
      setText(el, sel ? fmt(drops) : "—");
      if (el.dataset.value !== String(drops)) el.dataset.value = String(drops);
      el.classList.toggle("bad", drops > 0);
      rows($("t-streams").tBodies[0], msg.streams.map((st) => [
        [
          [st.name], [fmt(st.frames + st.duplicates + st.stale), "n"], [fmt(st.frames), "n"],
          [fmt(st.duplicates), "n"], [fmt(st.stale), "n"], [`${st.matched_markers}/${st.model_markers}`, "n"],
        ],
        {
          "data-stream": String(st.id),
          title: `source ${st.source}${st.performer ? ` · performer ${st.performer}` : ""}`,
          className: sel && st.id === sel.id ? "sel" : "",
        },
      ]));
      const d = msg.drops;
      kv($("drops"), [
        ["queue full", fmt(d.queue_full), d.queue_full > 0],
        ["duplicate", fmt(d.duplicate), d.duplicate > 0],
        ["stale", fmt(d.stale), d.stale > 0],
        ["no layout", fmt(d.no_layout), d.no_layout > 0],
        ["unmatched", fmt(d.unmatched), d.unmatched > 0],
        ["not allowed", fmt(d.not_allowed), d.not_allowed > 0],
        ["bad packets", fmt(d.bad_packets), d.bad_packets > 0],
        ["send buffer", fmt(d.send_buffer), d.send_buffer > 0],
        ["send errors", fmt(d.send_errors), d.send_errors > 0],
        ["missing markers", fmt(msg.missing_markers)],
        ["glitches", fmt(msg.glitches)],
        ["control refused", fmt(msg.control_refused), msg.control_refused > 0],
      ]);
      const lat = msg.latency || {};
      rows($("t-latency").tBodies[0], [["received → processed", lat.processed], ["processed → sent", lat.sent]]
        .map(([name, q]) => [[
          [name], [fmt(q && q.p50), "n"], [fmt(q && q.p99), "n"], [fmt(q && q.p50_all), "n"], [fmt(q && q.p99_all), "n"],
        ]]));
      const badge = $("latency-badge");
      const p99 = lat.processed ? lat.processed.p99 : null;
      setText(badge, p99 === null ? "—" : `p99 ${fmt(p99)} µs`);
      setClass(badge, "pill mono " + (p99 === null ? "" : p99 > 2000 ? "bad" : p99 > 500 ? "warn" : "on"));
      rows($("t-subs").tBodies[0], msg.subscribers.map((s) => [[
        [s.address], [s.profile], [s.performer || "all"],
        [s.lease_ms === null ? "static" : `${(s.lease_ms / 1000).toFixed(1)} s`, "n"],
        [fmt(s.sends), "n"], [fmt(s.failures), "n"],
      ]]));
      natnetServer((msg.sources || {}).natnet_server);
      const rec = msg.recording;
      const state = $("rec-state");
      setText(state, rec ? `recording ${rec.path}${rec.raw ? ` + ${rec.raw}` : ""}` : "idle");
      setClass(state, "pill " + (rec ? "bad" : "off"));
      const mon = msg.monitor;
      setText($("monitor-line"), `monitor: ${mon.viewers} page(s) open · ${fmt(mon.dropped)} feed messages dropped for slow pages · ${fmt(mon.refused)} requests refused`);
      setModel(selected);
    },
  };
}
