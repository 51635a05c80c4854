// The remount dialog's figure: the cube with the face the plan puts up, and its yaw seen from
// above (docs/web.md, "Live view"). The pose is the plan step's `remount` (one of the fixture's
// axes +x … -z pointing up) and `remount_yaw_deg` (the turn about the vertical after placing
// it, positive counter-clockwise seen from above: a right-handed turn about the up axis, as
// imucalib.plan.fixture_poses.rot_pm_for_pose applies it). Plain SVG, no build step.
"use strict";
window.RemountFigure = (function () {
  const NS = "http://www.w3.org/2000/svg";
  function el(name, attrs, text) {
    const node = document.createElementNS(NS, name);
    for (const [k, v] of Object.entries(attrs)) { node.setAttribute(k, String(v)); }
    if (text !== undefined) { node.textContent = text; }
    return node;
  }
  // Draw the pose into `svg` (emptied first); hide it when there is no remount.
  function draw(svg, face, yawDeg) {
    while (svg.firstChild) { svg.removeChild(svg.firstChild); }
    if (!face) { svg.setAttribute("hidden", ""); return; }
    const yaw = Number.isFinite(yawDeg) ? yawDeg : 0;
    svg.removeAttribute("hidden");
    svg.setAttribute("data-face", face);
    svg.setAttribute("data-yaw-deg", String(yaw));
    svg.setAttribute("viewBox", "0 0 260 150");
    svg.setAttribute("role", "img");
    svg.setAttribute("aria-label", `cube with face ${face} up, yaw ${yaw}°`);
    // side view: the cube in oblique projection, its top face (the one put up) shaded
    svg.appendChild(el("text", { x: 70, y: 14, class: "fig-title", "text-anchor": "middle" },
                       "side view"));
    svg.appendChild(el("polygon", { points: "30,60 90,60 90,130 30,130", class: "cube-side" }));
    svg.appendChild(el("polygon", { points: "90,60 110,40 110,110 90,130", class: "cube-side" }));
    svg.appendChild(el("polygon", { points: "30,60 50,40 110,40 90,60", class: "cube-up",
                                    id: "remount-face" }));
    svg.appendChild(el("text", { x: 70, y: 55, class: "face-label", "text-anchor": "middle",
                                 id: "remount-face-label" }, face));
    svg.appendChild(el("line", { x1: 70, y1: 36, x2: 70, y2: 22, class: "arrow" }));
    svg.appendChild(el("polygon", { points: "65,24 75,24 70,17", class: "arrowhead" }));
    svg.appendChild(el("text", { x: 60, y: 100, class: "fig-note", "text-anchor": "middle" },
                       `${face} up`));
    // top view: the table's reference direction dashed, the cube turned by the yaw
    const cx = 195, cy = 80;
    svg.appendChild(el("text", { x: cx, y: 14, class: "fig-title", "text-anchor": "middle" },
                       "top view"));
    svg.appendChild(el("line", { x1: cx, y1: cy, x2: cx, y2: cy - 62, class: "reference" }));
    // SVG's y points down: a counter-clockwise turn seen from above is a negative rotate()
    const turned = el("g", { transform: `rotate(${-yaw} ${cx} ${cy})`, id: "remount-yaw" });
    turned.appendChild(el("rect", { x: cx - 28, y: cy - 28, width: 56, height: 56,
                                    class: "cube-up" }));
    turned.appendChild(el("text", { x: cx, y: cy + 5, class: "face-label",
                                    "text-anchor": "middle" }, face));
    turned.appendChild(el("line", { x1: cx, y1: cy - 28, x2: cx, y2: cy - 46, class: "arrow" }));
    turned.appendChild(el("polygon", { points: `${cx - 5},${cy - 44} ${cx + 5},${cy - 44} `
                                               + `${cx},${cy - 52}`, class: "arrowhead" }));
    svg.appendChild(turned);
    svg.appendChild(el("text", { x: cx, y: 144, class: "fig-note", "text-anchor": "middle",
                                 id: "remount-yaw-label" }, `yaw ${yaw}°`));
  }
  return { draw };
})();
