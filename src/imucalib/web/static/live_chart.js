// Small SVG line charts for the run page's live view (no library, no build step).
// LiveChart.draw(svg, {series, band, xLabel, yLabel}) redraws `svg` from scratch:
//   series: [{points: [[x, y], ...], cls: "s0", markers: bool, errors: [e, ...] (± per point)}]
//   band:   {y0, y1} — a shaded horizontal band (the soak criterion), optional.
"use strict";
(function () {
  const NS = "http://www.w3.org/2000/svg";
  const PAD = { left: 58, right: 26, top: 24, bottom: 30 };

  function el(name, attrs, parent) {
    const node = document.createElementNS(NS, name);
    for (const [k, v] of Object.entries(attrs || {})) { node.setAttribute(k, String(v)); }
    if (parent) { parent.appendChild(node); }
    return node;
  }
  function text(parent, x, y, value, cls) {
    const node = el("text", { x, y, class: cls || "axis-label" }, parent);
    node.textContent = value;
    return node;
  }
  function fmt(v) {
    const a = Math.abs(v);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) { return v.toExponential(1); }
    return a >= 100 ? v.toFixed(0) : a >= 1 ? v.toFixed(2) : v.toPrecision(2);
  }
  function extent(values) {
    let lo = Infinity, hi = -Infinity;
    for (const v of values) { if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); } }
    if (!Number.isFinite(lo)) { return [0, 1]; }
    if (lo === hi) { const d = Math.abs(lo) * 0.01 || 1; return [lo - d, hi + d]; }
    const pad = (hi - lo) * 0.06;
    return [lo - pad, hi + pad];
  }

  function draw(svg, opts) {
    while (svg.firstChild) { svg.removeChild(svg.firstChild); }
    const box = svg.viewBox.baseVal;
    const w = box && box.width ? box.width : 640, h = box && box.height ? box.height : 200;
    const series = (opts.series || []).filter((s) => s.points && s.points.length);
    const xs = [], ys = [];
    for (const s of series) {
      s.points.forEach((p, i) => {
        xs.push(p[0]);
        const e = s.errors ? s.errors[i] || 0 : 0;
        ys.push(p[1] - e, p[1] + e);
      });
    }
    if (opts.band) { ys.push(opts.band.y0, opts.band.y1); }
    const [x0, x1] = extent(xs), [y0, y1] = extent(ys);
    const X = (x) => PAD.left + (x - x0) / (x1 - x0) * (w - PAD.left - PAD.right);
    const Y = (y) => h - PAD.bottom - (y - y0) / (y1 - y0) * (h - PAD.top - PAD.bottom);
    el("rect", { x: PAD.left, y: PAD.top, width: w - PAD.left - PAD.right,
                 height: h - PAD.top - PAD.bottom, class: "plot-area" }, svg);
    if (opts.band) {
      const top = Y(opts.band.y1), bottom = Y(opts.band.y0);
      el("rect", { x: PAD.left, y: top, width: w - PAD.left - PAD.right,
                   height: Math.max(bottom - top, 1), class: "band" }, svg);
    }
    for (let i = 0; i <= 4; i++) {
      const yv = y0 + (y1 - y0) * i / 4, yp = Y(yv);
      el("line", { x1: PAD.left, x2: w - PAD.right, y1: yp, y2: yp, class: "grid" }, svg);
      text(svg, PAD.left - 4, yp + 4, fmt(yv), "axis-label y");
      const xv = x0 + (x1 - x0) * i / 4;
      text(svg, X(xv), h - PAD.bottom + 14, fmt(xv), "axis-label x");
    }
    if (opts.xLabel) { text(svg, w - PAD.right, h - 3, opts.xLabel, "axis-label x-end"); }
    if (opts.yLabel) { text(svg, 4, 14, opts.yLabel, "axis-label"); }
    for (const s of series) {
      const cls = "series " + (s.cls || "s0");
      if (s.points.length > 1 && !s.markers) {
        const d = s.points.filter((p) => Number.isFinite(p[1]))
          .map((p, i) => `${i ? "L" : "M"}${X(p[0]).toFixed(1)},${Y(p[1]).toFixed(1)}`).join("");
        el("path", { d, class: cls + (s.dashed ? " dashed" : "") }, svg);
      }
      if (s.markers || s.points.length === 1) {
        s.points.forEach((p, i) => {
          if (!Number.isFinite(p[1])) { return; }
          const e = s.errors ? s.errors[i] || 0 : 0;
          if (e > 0) {
            el("line", { x1: X(p[0]), x2: X(p[0]), y1: Y(p[1] - e), y2: Y(p[1] + e),
                         class: cls + " error-bar" }, svg);
          }
          el("circle", { cx: X(p[0]), cy: Y(p[1]), r: 3, class: cls + " marker" }, svg);
        });
      }
    }
    if (opts.legend) {
      opts.legend.forEach((item, i) => {
        const x = PAD.left + 60 + i * 100;
        el("line", { x1: x, x2: x + 16, y1: 10, y2: 10, class: "series " + item.cls }, svg);
        text(svg, x + 20, 14, item.label, "legend");
      });
    }
  }
  window.LiveChart = { draw };
})();
