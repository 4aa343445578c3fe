// The map as SVG, drawn from the layout the server computed (GET /tableaux/{id}/layout): nothing is
// placed here, only scaled to the panel. Coordinates are metres with y up; the SVG's y goes down.

const NS = "http://www.w3.org/2000/svg";
const WIDTH = 640, HEIGHT = 460, MARGIN = 46;

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
export function drawMap(svg, drawing, handlers) {
  const { layout, map: m } = drawing;
  svg.replaceChildren();
  svg.setAttribute("viewBox", `0 0 ${WIDTH} ${HEIGHT}`);
  const defs = el("defs", {}, svg);
  const marker = el("marker", { id: "arrow", viewBox: "0 0 10 10", refX: 9, refY: 5, markerWidth: 7,
                                markerHeight: 7, orient: "auto-start-reverse" }, defs);
  el("path", { d: "M 0 0 L 10 5 L 0 10 z", class: "arrowhead" }, marker);
  const at = scaler(layout.bounds);
  const rel = relations(m);
  const paths = el("g", { class: "paths" }, svg);
  const places = el("g", { class: "places" }, svg);
  const nDstates = Object.keys(layout.dstates).length;
  const unfolded = nDstates <= 120;  // a big map starts folded: places only, unfold one by clicking it

  for (const [name, p] of Object.entries(layout.paths)) {
    const pts = shorten(p.points.map(at), 16);
    const line = el("g", { class: "path", "data-path": name }, paths);
    const points = pts.map((q) => q.join(",")).join(" ");
    el("polyline", { class: "line", points, "marker-end": "url(#arrow)" }, line);
    el("polyline", { class: "hit", points }, line);  // a wide, invisible stroke: easy to hover
    const mid = pts[Math.floor((pts.length - 1) / 2)], next = pts[Math.floor((pts.length - 1) / 2) + 1] || mid;
    text(paths, (mid[0] + next[0]) / 2 + 6, (mid[1] + next[1]) / 2 - 6, name, "path-label");
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
    const g = el("g", { class: unfolded ? "place unfolded" : "place", "data-place": name }, places);
    const [x, y] = at(place.xy);
    for (const d of place.dstates) {
      const ds = layout.dstates[d], info = m.dstates[d];
      const [dx, dy] = at(ds.xy);
      const dg = el("g", { class: "dstate", "data-dstate": d, tabindex: 0 }, g);
      el("line", { x1: x, y1: y, x2: dx, y2: dy, class: "spoke" }, dg);
      el("circle", { cx: dx, cy: dy, r: 7 }, dg);
      // The label further out along the spoke, anchored on the side away from the place.
      const len = Math.hypot(dx - x, dy - y) || 1, ux = (dx - x) / len, uy = (dy - y) / len;
      const label = text(dg, dx + ux * 10, dy + uy * 10 + (Math.abs(ux) > 0.3 ? 4 : uy > 0 ? 10 : -2),
                         info.view.length <= 4 ? `${d} ${info.view}` : d, "dstate-label");  // long views: on hover
      label.setAttribute("text-anchor", ux < -0.3 ? "end" : ux > 0.3 ? "start" : "middle");
      const heading = info.heading_deg === null ? "" : `, heading ${info.heading_deg}°`;
      el("title", {}, dg).textContent = `${d}: view ${info.view}${heading}` +
        (info.path ? `, on ${info.path} facing ${info.dir}` : "");
      dg.addEventListener("click", (e) => { e.stopPropagation(); handlers.onDstate(d); });
    }
    const hub = el("g", { class: "hub" }, g);
    if (isPlace(name, place)) {
      el("circle", { cx: x, cy: y, r: 13 }, hub);
      text(hub, x, y + 4, name, "place-label");
    }
    const sides = [...m.right_of.filter(([p]) => p === name).map(([, pa]) => `right of ${pa}`),
                   ...m.left_of.filter(([p]) => p === name).map(([, pa]) => `left of ${pa}`)];
    const about = () => hoverText(name, place.dstates.map((d) => `${d} (${m.dstates[d].view}` +
      (m.dstates[d].heading_deg === null ? ")" : `, ${m.dstates[d].heading_deg}°)`)).join(", "),
      `on ${(rel.on[name] || []).join(", ") || "no path"}${sides.length ? "; " + sides.join(", ") : ""}`);
    hub.addEventListener("click", () => g.classList.toggle("unfolded"));
    hub.addEventListener("mouseenter", (e) => handlers.onHover(about(), e.clientX, e.clientY));
    hub.addEventListener("mouseleave", () => handlers.onHover(null));
  }
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
    node.closest(".place")?.classList.add("unfolded");
  }
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
