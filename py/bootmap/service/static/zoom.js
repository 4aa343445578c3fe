// Zoom and pan of an SVG by its viewBox: the wheel zooms about the pointer, a drag pans, a double-click
// on the background fits the whole drawing again; zoomIn, zoomOut and fit for buttons and keys (+, -, 0,
// and the arrows pan, when the SVG has focus). The view is kept across redraws (apply) until fit.
//
// The SVG keeps the home box's aspect ratio (the stylesheet's aspect-ratio), and every zoom scales width
// and height alike, so a map unit is as many px across as up and the point under the pointer stays put.

const STEP = 1.25;          // a button's or a key's zoom
const MIN_SCALE = 0.5;      // zoomed out to twice the whole map at most
const MAX_SCALE = 40;       // zoomed in to a fortieth of it
const DRAG_PX = 4;          // a press moved less than this is a click, not a drag

export class ZoomView {
  // svg: the element; home: [x, y, width, height], the whole drawing; onChange(scale): the view changed,
  // scale is the screen px per map unit.
  constructor(svg, home, onChange) {
    Object.assign(this, { svg, home, onChange, box: [...home] });
    svg.addEventListener("wheel", (e) => this.#wheel(e), { passive: false });
    svg.addEventListener("pointerdown", (e) => this.#press(e));
    svg.addEventListener("dblclick", (e) => { if (!e.target.closest(".dstate, .hub")) this.fit(); });
    svg.addEventListener("keydown", (e) => this.#key(e));
    // A drag ends in a click on whatever is under the pointer: it is not one.
    svg.addEventListener("click", (e) => { if (this.dragged) { e.stopPropagation(); e.preventDefault(); } }, true);
    new ResizeObserver(() => this.apply()).observe(svg);
  }

  // Screen px per map unit (the SVG's scale on screen), 0 when it is not laid out.
  scale() {
    const ctm = this.svg.getScreenCTM();
    return ctm ? Math.hypot(ctm.a, ctm.b) : 0;
  }

  // The map point under client coordinates.
  point(clientX, clientY) {
    const ctm = this.svg.getScreenCTM();
    if (!ctm) return null;
    const p = new DOMPoint(clientX, clientY).matrixTransform(ctm.inverse());
    return [p.x, p.y];
  }

  apply() {
    this.svg.setAttribute("viewBox", this.box.map((v) => +v.toFixed(3)).join(" "));
    this.onChange(this.scale());
  }

  fit() {
    this.box = [...this.home];
    this.apply();
  }

  // Zoom by factor (> 1 zooms in) about a map point (the view's centre by default).
  zoom(factor, about = null) {
    const [x, y, w, h] = this.box;
    const now = this.home[2] / w;
    const to = Math.min(MAX_SCALE, Math.max(MIN_SCALE, now * factor));
    const k = now / to;  // the new width over the old
    const [px, py] = about ?? [x + w / 2, y + h / 2];
    this.box = [px - (px - x) * k, py - (py - y) * k, w * k, h * k];
    this.apply();
  }

  zoomIn() { this.zoom(STEP); }
  zoomOut() { this.zoom(1 / STEP); }

  // Pan by (dx, dy) map units: the drawing moves that way.
  pan(dx, dy) {
    const [x, y, w, h] = this.box;
    this.box = [x - dx, y - dy, w, h];
    this.apply();
  }

  #wheel(e) {
    e.preventDefault();  // the wheel over the map zooms it, not the page
    const lines = e.deltaMode === 1 ? 16 : e.deltaMode === 2 ? 400 : 1;
    const dy = Math.max(-300, Math.min(300, e.deltaY * lines));
    const at = this.point(e.clientX, e.clientY);
    if (at) this.zoom(Math.exp(-dy * 0.002), at);
  }

  #press(e) {
    if (e.button !== 0 || !e.isPrimary) return;
    this.dragged = false;
    const start = [e.clientX, e.clientY], box = [...this.box], scale = this.scale();
    if (!(scale > 0)) return;
    const move = (m) => {
      const dx = m.clientX - start[0], dy = m.clientY - start[1];
      if (!this.dragged) {
        if (Math.hypot(dx, dy) < DRAG_PX) return;
        // Captured only once it is a drag: a capture at the press would send a click to the SVG, not
        // to the dstate under it.
        this.dragged = true;
        this.svg.setPointerCapture(m.pointerId);
        this.svg.classList.add("panning");
      }
      this.box = [box[0] - dx / scale, box[1] - dy / scale, box[2], box[3]];
      this.apply();
    };
    const up = () => {
      this.svg.removeEventListener("pointermove", move);
      this.svg.removeEventListener("pointerup", up);
      this.svg.removeEventListener("pointercancel", up);
      this.svg.classList.remove("panning");
      setTimeout(() => { this.dragged = false; });  // after the click that ends it
    };
    this.svg.addEventListener("pointermove", move);
    this.svg.addEventListener("pointerup", up);
    this.svg.addEventListener("pointercancel", up);
  }

  #key(e) {
    if (e.ctrlKey || e.metaKey || e.altKey) return;
    const step = this.box[2] / 10;
    const act = { "+": () => this.zoomIn(), "=": () => this.zoomIn(), "-": () => this.zoomOut(),
                  "_": () => this.zoomOut(), "0": () => this.fit(),
                  ArrowLeft: () => this.pan(step, 0), ArrowRight: () => this.pan(-step, 0),
                  ArrowUp: () => this.pan(0, step), ArrowDown: () => this.pan(0, -step) }[e.key];
    if (!act) return;
    e.preventDefault();
    act();
  }
}
