// The map as SVG, drawn from the layout the server computed (GET /tableaux/{id}/layout): nothing is
// placed here, only scaled to the panel. Coordinates are metres with y up; the SVG's y goes down.

const NS = "http://www.w3.org/2000/svg";
export const WIDTH = 640, HEIGHT = 460;
const MARGIN = 46;
// A dstate's or a path's label shows when the nearest other one is at least this far on screen (px);
// closer, it shows only when its dstate is hovered, focused or picked: zoom in to see them all.
const LABEL_ROOM_PX = 36;

function el(name, attrs = {}, parent = null) {
  const node = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  if (parent) parent.appendChild(node);
  return node;
}

// Hover text as DOM nodes, never HTML (names and views are strings users posted): the name in bold,
// then lines of text. A fresh fragment each call: appending one empties it.
function hoverText(name, first, ...more) {
  const out = document.createDocumentFragment();
  out.append(Object.assign(document.createElement("b"), { textContent: name }), `: ${first}`);
  for (const line of more) out.append(document.createElement("br"), line);
  return out;
}

function text(parent, x, y, content, cls) {
  const t = el("text", { x, y, class: cls }, parent);
  t.textContent = content;
  return t;
}

// Metres -> panel pixels, keeping the aspect ratio (a metre is as long across as up).
function scaler(bounds, width = WIDTH, height = HEIGHT) {
  const [x0, y0, x1, y1] = bounds;
  const span = Math.max(x1 - x0, y1 - y0, 1e-9);
  const k = Math.min((width - 2 * MARGIN) / Math.max(x1 - x0, span * 0.05),
                     (height - 2 * MARGIN) / Math.max(y1 - y0, span * 0.05));
  const cx = (width - k * (x1 - x0)) / 2, cy = (height - k * (y1 - y0)) / 2;
  return ([x, y]) => [cx + k * (x - x0), height - cy - k * (y - y0)];
}

function relations(m) {
  const right = {}, left = {}, on = {};
  for (const [p, path] of m.right_of) (right[path] ||= []).push(p);
  for (const [p, path] of m.left_of) (left[path] ||= []).push(p);
  for (const [p, path] of m.on) (on[p] ||= []).push(path);
  return { right, left, on };
}

// Draw the map into svg. handlers: onDstate(name), onHover(nodes or null, clientX, clientY).
// Layers, bottom to top: paths, spokes, places (circles), dstates, places' names, so that a click on a
// dstate is the dstate's even where it lies on a place's circle (the names let clicks through). A place's spokes and dstates are a "fan" each
// (data-of: the place), folded and unfolded with it.
export function drawMap(svg, drawing, handlers) {
  const { layout, map: m } = drawing;
  svg.replaceChildren();
  svg.setAttribute("viewBox", `0 0 ${WIDTH} ${HEIGHT}`);
  const defs = el("defs", {}, svg);
  const marker = el("marker", { id: "arrow", viewBox: "0 0 10 10", refX: 9, refY: 5, markerWidth: 5,
                                markerHeight: 5, orient: "auto-start-reverse" }, defs);
  el("path", { d: "M 0 0 L 10 5 L 0 10 z", class: "arrowhead" }, marker);
  const at = scaler(layout.bounds);
  const rel = relations(m);
  const paths = el("g", { class: "paths" }, svg);
  const spokes = el("g", { class: "spokes" }, svg);
  const places = el("g", { class: "places" }, svg);
  const dstates = el("g", { class: "dstates" }, svg);
  const names = el("g", { class: "place-labels" }, svg);
  const nDstates = Object.keys(layout.dstates).length;
  const unfolded = nDstates <= 120;  // a big map starts folded: places only, unfold one by clicking it
  const pathLabels = [], dstateNodes = [];

  for (const [name, p] of Object.entries(layout.paths)) {
    const pts = shorten(p.points.map(at), 16);
    const line = el("g", { class: "path", "data-path": name }, paths);
    const points = pts.map((q) => q.join(",")).join(" ");
    el("polyline", { class: "line", points, "marker-end": "url(#arrow)" }, line);
    el("polyline", { class: "hit", points }, line);  // a wide, invisible stroke: easy to hover
    const mid = pts[Math.floor((pts.length - 1) / 2)], next = pts[Math.floor((pts.length - 1) / 2) + 1] || mid;
    const lx = (mid[0] + next[0]) / 2, ly = (mid[1] + next[1]) / 2;
    const label = text(paths, lx, ly, name, "path-label");
    label.setAttribute("dx", "0.5em");
    label.setAttribute("dy", "-0.5em");
    pathLabels.push([label, lx, ly]);
    const describe = () => hoverText(name, p.places.join(" → "),
                                     `right of it: ${(rel.right[name] || []).join(", ") || "—"}`,
                                     `left of it: ${(rel.left[name] || []).join(", ") || "—"}`);
    line.addEventListener("mouseenter", (e) => {
      mark(svg, "right-of", rel.right[name] || []);
      mark(svg, "left-of", rel.left[name] || []);
      line.classList.add("hovered");
      handlers.onHover(describe(), e.clientX, e.clientY);
    });
    line.addEventListener("mouseleave", () => {
      mark(svg, "right-of", []);
      mark(svg, "left-of", []);
      line.classList.remove("hovered");
      handlers.onHover(null);
    });
  }

  for (const [name, place] of Object.entries(layout.places)) {
    const fold = unfolded ? " unfolded" : "";
    const g = el("g", { class: "place" + fold, "data-place": name }, places);
    const spokeFan = el("g", { class: "fan" + fold, "data-of": name }, spokes);
    const fan = el("g", { class: "fan" + fold, "data-of": name }, dstates);
    const [x, y] = at(place.xy);
    for (const d of place.dstates) {
      const ds = layout.dstates[d], info = m.dstates[d];
      const [dx, dy] = at(ds.xy);
      el("line", { x1: x, y1: y, x2: dx, y2: dy, class: "spoke" }, spokeFan);
      const dg = el("g", { class: "dstate", "data-dstate": d, tabindex: 0 }, fan);
      el("circle", { cx: dx, cy: dy, r: 7 }, dg);
      // The label further out along the spoke, anchored on the side away from the place (baselines,
      // not offsets in units, so that it sits right whatever its size).
      const len = Math.hypot(dx - x, dy - y) || 1, ux = (dx - x) / len, uy = (dy - y) / len;
      const side = Math.abs(ux) > 0.3 ? "central" : uy > 0 ? "hanging" : "alphabetic";
      const label = text(dg, dx + ux * 10, dy + uy * 10, info.view.length <= 4 ? `${d} ${info.view}` : d,
                         "dstate-label");  // long views: on hover
      label.setAttribute("text-anchor", ux < -0.3 ? "end" : ux > 0.3 ? "start" : "middle");
      label.setAttribute("dominant-baseline", side);
      const heading = info.heading_deg === null ? "" : `, heading ${info.heading_deg}°`;
      el("title", {}, dg).textContent = `${d}: view ${info.view}${heading}` +
        (info.path ? `, on ${info.path} facing ${info.dir}` : "");
      dg.addEventListener("click", (e) => { e.stopPropagation(); handlers.onDstate(d); });
      dstateNodes.push([dg, dx, dy]);
    }
    const hub = el("g", { class: "hub" }, g);
    if (isPlace(name, place)) {
      el("circle", { cx: x, cy: y, r: 13 }, hub);
      text(names, x, y, name, "place-label").setAttribute("dominant-baseline", "central");
    }
    const sides = [...m.right_of.filter(([p]) => p === name).map(([, pa]) => `right of ${pa}`),
                   ...m.left_of.filter(([p]) => p === name).map(([, pa]) => `left of ${pa}`)];
    const about = () => hoverText(name, place.dstates.map((d) => `${d} (${m.dstates[d].view}` +
      (m.dstates[d].heading_deg === null ? ")" : `, ${m.dstates[d].heading_deg}°)`)).join(", "),
      `on ${(rel.on[name] || []).join(", ") || "no path"}${sides.length ? "; " + sides.join(", ") : ""}`);
    hub.addEventListener("click", () => unfold(svg, name, !g.classList.contains("unfolded")));
    hub.addEventListener("mouseenter", (e) => handlers.onHover(about(), e.clientX, e.clientY));
    hub.addEventListener("mouseleave", () => handlers.onHover(null));
  }
  room(dstateNodes);
  room(pathLabels);
}

// Each node's distance to the nearest other (map units) as its data-room: fitLabels hides the labels
// that have too little room at the present zoom. A grid of cells as wide as the median spacing would
// do for thousands; a few hundred nodes, every pair, take a millisecond.
function room(nodes) {
  for (const [node, x, y] of nodes) {
    let best = Infinity;
    for (const [other, ox, oy] of nodes) if (other !== node) best = Math.min(best, Math.hypot(ox - x, oy - y));
    node.dataset.room = String(best);
  }
}

// Labels for the present screen scale (px per map unit): the stylesheet sizes them in px times --u
// (units per px), so that they are as large on screen whatever the zoom or the window, and lines and
// arrowheads are as thick; labels with less room than LABEL_ROOM_PX around them are folded away
// ("crowded") until a zoom gives them room.
export function fitLabels(svg, scale) {
  if (!(scale > 0)) return;
  svg.style.setProperty("--u", String(1 / scale));
  crowd(svg, scale);
}

function crowd(svg, scale) {
  for (const node of svg.querySelectorAll("[data-room]")) {
    node.classList.toggle("crowded", Number(node.dataset.room) * scale < LABEL_ROOM_PX);
  }
}

// Fold or unfold a place's dstates.
function unfold(svg, place, on) {
  svg.querySelector(`.place[data-place="${CSS.escape(place)}"]`)?.classList.toggle("unfolded", on);
  for (const fan of svg.querySelectorAll(`.fan[data-of="${CSS.escape(place)}"]`)) fan.classList.toggle("unfolded", on);
}

// The map as it is drawn, as a standalone SVG file: the present view (viewBox), at the panel's size in
// px, with the page's rules for what it holds in a <style> of its own (so it renders outside the page).
export function svgFile(svg) {
  const copy = svg.cloneNode(true);
  const [, , w] = (svg.getAttribute("viewBox") || `0 0 ${WIDTH} ${HEIGHT}`).split(/[\s,]+/).map(Number);
  copy.removeAttribute("id");
  copy.removeAttribute("tabindex");
  copy.setAttribute("width", WIDTH);
  copy.setAttribute("height", HEIGHT);
  copy.style.setProperty("--u", String(w / WIDTH));  // labels as large in the file as on screen
  crowd(copy, WIDTH / w);  // and shown where the file's size gives them room
  copy.style.setProperty("background", "#fff");
  const rules = [];
  for (const sheet of document.styleSheets) {
    let list;
    try { list = sheet.cssRules; } catch { continue; }
    for (const rule of list) {
      if (!(rule instanceof CSSStyleRule)) continue;
      let used = rule.selectorText === ":root";
      try { used ||= copy.querySelector(rule.selectorText) !== null; } catch { /* a selector this browser has no use for */ }
      if (used) rules.push(rule.cssText);
    }
  }
  const style = document.createElementNS(NS, "style");
  style.textContent = "\n" + rules.join("\n") + "\n";
  copy.insertBefore(style, copy.firstChild);
  return '<?xml version="1.0" encoding="UTF-8"?>\n' + new XMLSerializer().serializeToString(copy) + "\n";
}

// A map without places (topological level off) has one node per dstate: no place circle then.
function isPlace(name, place) {
  return !(place.dstates.length === 1 && place.dstates[0] === name);
}

// Pull a polyline's ends back from the place circles so the arrowhead shows.
function shorten(points, by) {
  if (points.length < 2) return points;
  const out = points.map((p) => [...p]);
  const pull = (a, b) => {
    const dx = b[0] - a[0], dy = b[1] - a[1], len = Math.hypot(dx, dy);
    if (len > 2 * by) { a[0] += (dx / len) * by; a[1] += (dy / len) * by; }
  };
  pull(out[0], points[1]);
  pull(out[out.length - 1], points[points.length - 2]);
  return out;
}

function mark(svg, cls, places) {
  for (const node of svg.querySelectorAll(`.${cls}`)) node.classList.remove(cls);
  for (const p of places) svg.querySelector(`[data-place="${CSS.escape(p)}"]`)?.classList.add(cls);
}

// Light the given dstates (class "lit"), and unfold their places so they show.
export function light(svg, cls, dstates) {
  for (const node of svg.querySelectorAll(`.dstate.${cls}`)) node.classList.remove(cls);
  for (const d of dstates) {
    const node = svg.querySelector(`.dstate[data-dstate="${CSS.escape(d)}"]`);
    if (!node) continue;
    node.classList.add(cls);
    const fan = node.closest(".fan");
    if (fan) unfold(svg, fan.dataset.of, true);
  }
}

// Give the given dstates the class cls (and no others), leaving their places folded as they are.
export function markDstates(svg, cls, dstates) {
  for (const node of svg.querySelectorAll(`.dstate.${cls}`)) node.classList.remove(cls);
  for (const d of dstates) svg.querySelector(`.dstate[data-dstate="${CSS.escape(d)}"]`)?.classList.add(cls);
}

// The true trajectory (poses), in its own frame, with the start marked.
export function drawTrajectory(svg, points) {
  svg.replaceChildren();
  const w = 420, h = 300;
  svg.setAttribute("viewBox", `0 0 ${w} ${h}`);
  const xs = points.map((p) => p[0]), ys = points.map((p) => p[1]);
  const at = scaler([Math.min(...xs), Math.min(...ys), Math.max(...xs), Math.max(...ys)], w, h);
  el("polyline", { class: "trajectory", points: points.map((p) => at(p).join(",")).join(" ") }, svg);
  const [sx, sy] = at(points[0]);
  el("circle", { cx: sx, cy: sy, r: 5, class: "start" }, svg);
  text(svg, sx + 7, sy - 7, "t0", "dstate-label");
}
