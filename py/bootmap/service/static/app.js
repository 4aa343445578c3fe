// The viewer: pick a tableau, draw its map, link the table to it, ask why, follow appended steps.
//
// Live updates poll the layout once a second with If-None-Match: the server answers 304 (no body, one
// read of the stored map) until an append makes a new revision. Polling rather than server-sent events
// because EventSource cannot send the Authorization header, and because an append may land through
// another server process on the same database, which a per-process event stream would not hear of.

import { ApiError, askToken, getJSON, objectURL, sendJSON } from "./api.js";
import { changedDstates, renderAssertions, renderConflict, renderDiff } from "./assert.js";
import { HEIGHT, WIDTH, drawMap, drawTrajectory, fitLabels, light, markDstates, svgFile } from "./draw.js";
import { fillTable, markRows } from "./table.js";
import { renderWhy } from "./why.js";
import { ZoomView } from "./zoom.js";

const POLL_MS = 1000;
const $ = (id) => document.getElementById(id);
const state = { id: null, etag: null, drawing: null, picks: [], poll: null, levels: [], whyAsked: 0, view: null,
                changed: [], listed: 0 };

function status(message, isError = false) {
  $("status").textContent = message;
  $("status").classList.toggle("error", isError);
}

function fail(e) {
  // An ApiError is the service's own answer (problem details): shown, not thrown to the console.
  status(e instanceof ApiError ? `${e.status}: ${e.message}` : `error: ${e.message}`, true);
}

async function listTableaux(selected) {
  const { data } = await getJSON("/tableaux?limit=1000");
  const select = $("tableaux");
  select.replaceChildren(...(data.items.length ? [] : [new Option("no tableaux stored yet", "")]));
  for (const it of data.items) {
    const o = new Option(`#${it.id}: ${it.steps} steps, ${it.dstates} dstates, ${it.places} places, ` +
                         `${it.paths} paths (rev ${it.revision})`, it.id);
    select.add(o);
  }
  const pick = selected ?? data.items[0]?.id;
  if (pick !== undefined) select.value = String(pick);
  return pick;
}

async function loadLevels(chosen) {
  const { data } = await getJSON("/axioms");
  const box = $("levels");
  box.querySelectorAll("label").forEach((l) => l.remove());
  for (const level of data.levels) {
    const label = document.createElement("label");
    const input = Object.assign(document.createElement("input"), { type: "checkbox", value: level, name: "level" });
    input.checked = !chosen || chosen.includes(level);
    label.append(input, ` ${level}`);
    box.append(label);
  }
  state.levels = data.levels;
}

function chosenLevels() {
  const on = [...$("levels").querySelectorAll("input:checked")].map((i) => i.value);
  return on.length === state.levels.length ? null : on;  // null: the service's default, every level
}

async function openTableau(id) {
  clearTimeout(state.poll);
  Object.assign(state, { id, etag: null, drawing: null, picks: [], changed: [] });
  $("why").replaceChildren();
  $("asserted").replaceChildren();
  $("assertions-panel").hidden = true;
  if (id === undefined || id === null || id === "") return;
  const url = new URL(location.href);
  url.searchParams.set("tableau", id);
  history.replaceState(null, "", url);
  await refresh();
  loadAssertions().catch(fail);
  poll();
}

// Fetch the layout; redraw when it changed (a new revision). Returns whether it did.
async function refresh() {
  const id = state.id;
  const got = await getJSON(`/tableaux/${id}/layout`, { etag: state.etag });
  if (got.notModified || id !== state.id) return false;
  const revised = state.drawing !== null;
  state.etag = got.etag;
  state.drawing = got.data;
  draw();
  if (revised) state.view.apply(); else state.view.fit();  // a new revision keeps the user's zoom
  if (revised) listTableaux(id).catch(fail);  // the list shows steps and counts: new ones now
  return true;
}

function draw() {
  const d = state.drawing, m = d.map, s = m.summary;
  drawMap($("map"), d, { onDstate: (name) => pick({ dstate: name }), onHover: hover });
  $("layout-method").textContent = {
    metrical: `(laid out by headings and travels; closes to ${(d.layout.closure_rms_m ?? 0).toFixed(3)} m RMS)`,
    odometry: "(laid out at the robot's own dead-reckoned positions: the travels do not close)",
  }[d.layout.method] ?? "(laid out by travel distances: no headings, or the travels do not close)";
  $("summary").textContent = `${s.dstates} dstates, ${s.places} places, ${s.paths} paths; revision ${d.revision}` +
    (s.found_by === "loop closing" ? "; loop-closed from odometry (not minimal)"
      : s.unique ? "; unique minimal map" : `; ${s.minimal_maps}${s.minimal_maps_capped ? "+" : ""} minimal maps`);
  // Measured by the tests and the benchmark: the map is on the page.
  document.body.dataset.drawn = String(d.revision);
  window.bootmapTimes = { ...(window.bootmapTimes || {}), drawn: performance.now() };
  fillTable($("tableau"), m.steps, (t) => pick({ t }));
  // How sure the map is: the dstates the minimal maps disagree on, dashed; what the last assertion changed.
  const c = m.confidence;
  markDstates($("map"), "unsettled", c ? Object.keys(c.dstates).filter((d) => c.dstates[d].in_maps < c.minimal_maps) : []);
  markDstates($("map"), "changed", state.changed);
  if (c && (c.minimal_maps > 1 || c.capped)) {
    $("summary").textContent += `; ${Math.round(100 * c.settled)}% of time points at a dstate they all agree on`;
  }
  const traj = d.layout.trajectory;
  $("truth-panel").hidden = !traj;
  if (traj) drawTrajectory($("trajectory"), traj);
  showPicks();
}

// The hover box: nodes drawMap built (text, never HTML), or null to hide it.
function hover(nodes, x, y) {
  const box = $("hover");
  if (!nodes) { box.hidden = true; return; }
  box.replaceChildren(nodes);
  box.style.left = `${x + 14}px`;
  box.style.top = `${y + 14}px`;
  box.hidden = false;
}

// A click on a dstate or a time point. The first lights up; the second asks why.
function pick(p) {
  const rows = state.drawing.map.steps;
  const t = p.t ?? rows.findIndex((r) => r.dstate === p.dstate);  // a dstate stands for its first visit
  const picked = { t, label: p.dstate ?? `t${t}`, dstate: rows[t].dstate };
  state.picks = state.picks.length >= 2 ? [picked] : [...state.picks, picked];
  showPicks();
  if (state.picks.length === 2) why(state.picks[0], state.picks[1]);
}

function showPicks() {
  if (!state.drawing) return;
  const picks = state.picks.filter((p) => p.t < state.drawing.map.steps.length);
  light($("map"), "lit", picks.map((p) => p.dstate));
  markRows($("tableau"), "picked", picks.map((p) => p.t), true);
  $("selection").textContent = picks.length === 0 ? "Click two dstates (on the map) or two time points (rows)."
    : picks.length === 1 ? `${picks[0].label} (${picks[0].dstate} at t${picks[0].t}): click another.`
    : `${picks[0].label} and ${picks[1].label}:`;
  const two = picks.length === 2 && picks[0].t !== picks[1].t;
  $("assert-same").disabled = $("assert-apart").disabled = !two;
}

// "Same place" or "Not the same" on the two picks: the map solved again around it, what changed lit on
// the new map; or the clash, with its proof.
async function assertPicked(kind) {
  const [a, b] = state.picks;
  const said = `${kind}(t${a.t}, t${b.t})`;
  document.body.dataset.asserted = "asking";
  $("asserted").replaceChildren(Object.assign(document.createElement("p"), {
    className: "busy", textContent: `${said}: solving the map again…` }));
  try {
    const { data } = await sendJSON("POST", `/tableaux/${state.id}/assertions`, { [kind]: [`t${a.t}`, `t${b.t}`] });
    await changed(data, said);
    document.body.dataset.asserted = "changed";
  } catch (e) {
    if (e instanceof ApiError && e.status === 409 && e.problem?.conflict) {
      renderConflict($("asserted"), e.problem, (t) => markRows($("tableau"), "focus", [t], true));
      markRows($("tableau"), "evidence", e.problem.conflict.explanation.evidence);
      document.body.dataset.asserted = "conflict";
    } else {
      $("asserted").replaceChildren();
      document.body.dataset.asserted = "failed";
      fail(e);
    }
  }
}

// A change the service made (an assertion added or taken back): say what changed, draw the new map.
async function changed(data, said) {
  state.changed = changedDstates(data.diff);
  state.picks = [];
  state.whyAsked++;  // an answer about the old map, still on its way, is not shown
  $("why").replaceChildren();
  markRows($("tableau"), "evidence", []);
  renderDiff($("asserted"), data.diff, said);
  await refresh();
  markDstates($("map"), "changed", state.changed);
  showAssertions(data.assertions);
}

async function loadAssertions() {
  const listed = state.listed;
  try {
    const { data } = await getJSON(`/tableaux/${state.id}/assertions`);
    // A list shown since it was asked for (an assertion made or taken back meanwhile) is newer: keep it.
    if (listed === state.listed) showAssertions(data.assertions);
  } catch (e) {
    // Another owner's (public) tableau: its assertions are not the reader's to see, nor to change.
    if (!(e instanceof ApiError && (e.status === 403 || e.status === 404))) throw e;
    $("assertions-panel").hidden = true;
  }
}

function showAssertions(assertions) {
  state.listed++;
  document.body.dataset.listed = state.listed;  // the assertions are listed (for scripts that drive the page)
  $("assertions-panel").hidden = false;
  renderAssertions($("assertions"), assertions, async (aid) => {
    document.body.dataset.asserted = "asking";
    try {
      const { data } = await sendJSON("DELETE", `/tableaux/${state.id}/assertions/${aid}`);
      await changed(data, `assertion ${aid} taken back`);
      document.body.dataset.asserted = "removed";
    } catch (e) {
      document.body.dataset.asserted = "failed";
      fail(e);
    }
  });
}

async function why(a, b) {
  const asked = ++state.whyAsked;
  const started = performance.now();
  document.body.dataset.why = "asking";
  const busy = Object.assign(document.createElement("p"), { className: "busy", textContent: "asking the solver…" });
  $("why").replaceChildren(busy);
  // Time points, not dstate names: the map with other levels may name its dstates differently.
  const q = new URLSearchParams({ a: `t${a.t}`, b: `t${b.t}` });
  const levels = chosenLevels();
  if (levels) q.set("levels", levels.join(","));
  try {
    const { data } = await getJSON(`/tableaux/${state.id}/why?${q}`);
    if (asked !== state.whyAsked) return;
    renderWhy($("why"), data, (t) => markRows($("tableau"), "focus", [t], true));
    markRows($("tableau"), "evidence", data.evidence);
    document.body.dataset.why = data.verdict;
    window.bootmapTimes = { ...(window.bootmapTimes || {}), why: performance.now() - started };
  } catch (e) {
    if (asked !== state.whyAsked) return;
    $("why").replaceChildren();
    document.body.dataset.why = "failed";
    fail(e);
  }
}

function poll() {
  state.poll = setTimeout(async () => {
    const id = state.id;
    try {
      if (!document.hidden && await refresh()) status(`revision ${state.drawing.revision} drawn`);
    } catch (e) {
      fail(e);
      if (e instanceof ApiError && e.status === 404) return;  // the tableau is gone: stop asking
    }
    if (id === state.id) poll();
  }, POLL_MS);
}

async function loadRuns() {
  const { data } = await getJSON("/runs");
  if (!data.runs.some((r) => r.figures.length)) return;
  const box = $("runs");
  for (const run of data.runs.filter((r) => r.figures.length)) {
    const details = document.createElement("details");
    details.className = "run";
    // As text: a run's name and world are strings from files, not markup.
    details.append(Object.assign(document.createElement("summary"), {
      textContent: `${run.name}${run.world ? ` — ${run.world}` : ""}` +
                   `${run.seed !== null ? `, seed ${run.seed}` : ""} (${run.figures.length} figures)` }));
    details.addEventListener("toggle", async () => {
      if (!details.open || details.dataset.loaded) return;
      details.dataset.loaded = "1";
      for (const name of run.figures) {
        const fig = document.createElement("figure");
        const img = Object.assign(document.createElement("img"), { alt: name });
        fig.append(img, Object.assign(document.createElement("figcaption"), { textContent: name }));
        details.append(fig);
        img.src = await objectURL(`/runs/figure?${new URLSearchParams({ run: run.name, name })}`);
      }
    });
    box.append(details);
  }
  $("runs-panel").hidden = false;
}

// A file to save: a link to a blob, clicked. The names say which tableau (and revision) it is.
function save(name, type, content) {
  const url = URL.createObjectURL(new Blob([content], { type }));
  const a = Object.assign(document.createElement("a"), { href: url, download: name });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10_000);
}

function fileName(ext) {
  return `bootmap-tableau-${state.id}-rev${state.drawing.revision}-map.${ext}`;
}

function mapTools() {
  const svg = $("map");
  state.view = new ZoomView(svg, [0, 0, WIDTH, HEIGHT], (scale) => fitLabels(svg, scale));
  $("zoom-in").addEventListener("click", () => state.view.zoomIn());
  $("zoom-out").addEventListener("click", () => state.view.zoomOut());
  $("zoom-fit").addEventListener("click", () => state.view.fit());
  $("save-svg").addEventListener("click", () => {
    if (state.drawing) save(fileName("svg"), "image/svg+xml", svgFile(svg));
  });
  // The map as the API serves it (GET /tableaux/{id}/map), not the layout around it.
  $("save-json").addEventListener("click", () => {
    if (state.drawing) save(fileName("json"), "application/json", JSON.stringify(state.drawing.map, null, 1) + "\n");
  });
}

async function main() {
  const params = new URLSearchParams(location.search);
  mapTools();
  $("token-button").addEventListener("click", () => askToken("The API token this tab sends (kept until the tab closes)."));
  $("tableaux").addEventListener("change", (e) => openTableau(e.target.value).catch(fail));
  $("assert-same").addEventListener("click", () => assertPicked("same"));
  $("assert-apart").addEventListener("click", () => assertPicked("apart"));
  try {
    await loadLevels(params.get("levels")?.split(","));
    const id = await listTableaux(params.get("tableau"));
    await openTableau(id);
    loadRuns().catch(fail);
  } catch (e) {
    fail(e);
  }
}

main();
