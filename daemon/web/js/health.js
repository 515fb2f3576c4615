// Health: frames in and out, drops by reason, stage latencies, subscribers and their leases,
// the model (file, markers matched, quality warnings), and the recording with its control.

const $ = (id) => document.getElementById(id);
const fmt = (v) => (v === null || v === undefined ? "—" : Number(v).toLocaleString("en-US"));

function cells(row, values) {
  row.replaceChildren(...values.map(([v, cls]) => {
    const td = document.createElement("td");
    td.textContent = v;
    if (cls) td.className = cls;
    return td;
  }));
  return row;
}

function kv(box, pairs) {
  box.replaceChildren(...pairs.map(([k, v, hot]) => {
    const d = document.createElement("div");
    const a = document.createElement("span");
    a.className = "dim";
    a.textContent = k;
    const b = document.createElement("span");
    b.textContent = v;
    if (hot) b.className = "hot";
    d.dataset.key = k;
    d.append(a, b);
    return d;
  }));
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
    $("warnings").replaceChildren(...warnings.map((w) => {
      const li = document.createElement("li");
      li.textContent = w;
      return li;
    }));
  }

  return {
    setModel,
    update(msg, selected) {
      status = msg;
      $("h-in").textContent = fmt(msg.frames_in);
      $("h-out").textContent = fmt(msg.frames_out);
      $("h-subs").textContent = fmt(msg.subscribers.length);
      const sel = selected && msg.streams.find((st) => st.id === selected.id);
      const drops = sel ? sel.duplicates + sel.stale : 0;
      const el = $("stream-drops");
      el.textContent = sel ? fmt(drops) : "—";
      el.dataset.value = String(drops);
      el.classList.toggle("bad", drops > 0);
      const body = $("t-streams").tBodies[0];
      body.replaceChildren(...msg.streams.map((st) => {
        const tr = cells(document.createElement("tr"), [
          [st.name], [fmt(st.frames + st.duplicates + st.stale), "n"], [fmt(st.frames), "n"],
          [fmt(st.duplicates), "n"], [fmt(st.stale), "n"], [`${st.matched_markers}/${st.model_markers}`, "n"],
        ]);
        tr.dataset.stream = st.id;
        tr.title = `source ${st.source}${st.performer ? ` · performer ${st.performer}` : ""}`;
        if (sel && st.id === sel.id) tr.className = "sel";
        return tr;
      }));
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
      $("t-latency").tBodies[0].replaceChildren(...[["received → processed", lat.processed], ["processed → sent", lat.sent]]
        .map(([name, q]) => cells(document.createElement("tr"), [
          [name], [fmt(q && q.p50), "n"], [fmt(q && q.p99), "n"], [fmt(q && q.p50_all), "n"], [fmt(q && q.p99_all), "n"],
        ])));
      const badge = $("latency-badge");
      const p99 = lat.processed ? lat.processed.p99 : null;
      badge.textContent = p99 === null ? "—" : `p99 ${fmt(p99)} µs`;
      badge.className = "pill mono " + (p99 === null ? "" : p99 > 2000 ? "bad" : p99 > 500 ? "warn" : "on");
      $("t-subs").tBodies[0].replaceChildren(...msg.subscribers.map((s) => cells(document.createElement("tr"), [
        [s.address], [s.profile], [s.performer || "all"],
        [s.lease_ms === null ? "static" : `${(s.lease_ms / 1000).toFixed(1)} s`, "n"],
        [fmt(s.sends), "n"], [fmt(s.failures), "n"],
      ])));
      const rec = msg.recording;
      const state = $("rec-state");
      state.textContent = rec ? `recording ${rec.path}${rec.raw ? ` + ${rec.raw}` : ""}` : "idle";
      state.className = "pill " + (rec ? "bad" : "off");
      const mon = msg.monitor;
      $("monitor-line").textContent = `monitor: ${mon.viewers} page(s) open · ${fmt(mon.dropped)} feed messages dropped for slow pages · ${fmt(mon.refused)} requests refused`;
      setModel(selected);
    },
  };
}
