// The components over the last seconds: one lane per component, each scaled to its own range
// in the window; the emotion components get taller lanes with the input beside the edit.

import { fit } from "./canvas.js";

export const HISTORY_S = 10;

export function createStrip(canvas) {
  return {
    draw(s) {
      const { g, w, h } = fit(canvas, "#151a21");
      const hist = s.history;
      if (!hist.length) return;
      const m = hist[hist.length - 1].uOut.length;
      const emotion = new Set(s.model ? s.model.emotion.components : []);
      const roles = s.model ? s.model.roles : [];
      const weight = (k) => (emotion.has(k) ? 3 : 1);
      const total = Array.from({ length: m }, (_, k) => weight(k)).reduce((a, b) => a + b, 0);
      const left = w < 500 ? 58 : 92;
      const right = w - 8;
      const now = hist[hist.length - 1].t;
      const x = (t) => right - ((now - t) / (HISTORY_S * 1000)) * (right - left);
      let top = 4;
      const unit = (h - 8) / Math.max(total, 1);
      g.font = "11px 'DejaVu Sans Mono', monospace";
      g.textBaseline = "middle";
      for (let k = 0; k < m; k++) {
        const lane = unit * weight(k);
        const emo = emotion.has(k);
        let lo = Infinity;
        let hi = -Infinity;
        for (const e of hist) {
          for (const v of emo ? [e.uIn[k], e.uOut[k]] : [e.uOut[k]]) {
            if (v < lo) lo = v;
            if (v > hi) hi = v;
          }
        }
        const pad = Math.max((hi - lo) * 0.1, 1e-3);
        lo -= pad;
        hi += pad;
        const y = (v) => top + lane - ((v - lo) / (hi - lo)) * lane;
        if (emo) {
          g.fillStyle = "rgba(242,163,58,.06)";
          g.fillRect(left, top, right - left, lane);
        }
        g.strokeStyle = "#1d2530";
        g.lineWidth = 1;
        g.beginPath(); g.moveTo(left, top + lane); g.lineTo(right, top + lane); g.stroke();
        g.fillStyle = emo ? "#f2a33a" : "#7d8795";
        const role = roles[k] && roles[k] !== "unknown" && roles[k] !== "other" ? ` ${roles[k]}` : "";
        if (lane >= 9) g.fillText(`c${k}${w < 500 ? "" : role}`, 4, top + lane / 2);
        const line = (pick, color, width, dash) => {
          g.strokeStyle = color;
          g.lineWidth = width;
          g.setLineDash(dash);
          g.beginPath();
          hist.forEach((e, i) => {
            const px = x(e.t);
            const py = y(pick(e)[k]);
            if (i === 0) g.moveTo(px, py); else g.lineTo(px, py);
          });
          g.stroke();
          g.setLineDash([]);
        };
        if (emo) {
          line((e) => e.uIn, "#7fb2ff", 1.4, [4, 3]);
          line((e) => e.uOut, "#f2a33a", 2, []);
        } else {
          line((e) => e.uOut, "#4b5563", 1, []);
        }
        top += lane;
      }
      g.fillStyle = "#7d8795";
      g.textAlign = "right";
      g.fillText(`−${HISTORY_S} s`, left + 34, h - 6);
      g.fillText("now", right, h - 6);
      g.textAlign = "left";
    },
  };
}
