// A canvas sized to its box at the screen's pixel ratio (sharp on a phone), cleared, ready to
// draw in CSS pixels. Opaque (painted `bg`): the browser composites it without blending, which
// is most of its cost where there is no GPU.

export function fit(canvas, bg = "#0f1319") {
  const dpr = window.devicePixelRatio || 1;
  const w = canvas.clientWidth;
  const h = canvas.clientHeight;
  if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
  }
  const g = canvas.getContext("2d", { alpha: false });
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.fillStyle = bg;
  g.fillRect(0, 0, w, h);
  return { g, w, h };
}
