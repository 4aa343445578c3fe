// A person's assertions as the page shows them: what changed when one was made or taken back (the
// dstates, places and paths joined or split), the clash when no map honours them (its proof, as why.js
// shows a proof), and the list of a tableau's assertions with a button to take each back.
// Every value goes through escape (table.js) or textContent: notes are what users wrote.

import { escape } from "./table.js";
import { renderWhy } from "./why.js";

// The dstates of the new map that a change made (joined into, or split out): the page lights them.
export function changedDstates(diff) {
  return [...diff.joined.map((j) => j.now), ...diff.split.flatMap((s) => s.now)];
}

export function renderDiff(el, diff, said) {
  const items = [];
  for (const [what, joined, split] of [["dstates", diff.joined, diff.split],
                                       ["places", diff.places_joined, diff.places_split],
                                       ["paths", diff.paths_joined, diff.paths_split]]) {
    for (const j of joined) items.push(`${what} ${j.was.join(" + ")} joined: now ${j.now}`);
    for (const s of split) items.push(`${what.slice(0, -1)} ${s.was} split: now ${s.now.join(", ")}`);
  }
  const counts = `${diff.dstates[0]} → ${diff.dstates[1]} dstates, ${diff.places[0]} → ${diff.places[1]} places, ` +
                 `${diff.paths[0]} → ${diff.paths[1]} paths`;
  el.innerHTML = `<p class="asserted-head">${escape(said)}: ${escape(counts)}</p>` +
    (items.length ? `<ul class="diff">${items.map((i) => `<li>${escape(i)}</li>`).join("")}</ul>`
      : `<p class="diff-none">nothing changed: the map already did that</p>`);
}

// A 409 from POST /tableaux/{id}/assertions: the clashing assertions and the proof.
export function renderConflict(el, problem, onStep) {
  const c = problem.conflict;
  const said = c.assertions.map((a) => (a.same ? `same(${a.same.join(", ")})` : `apart(${a.apart.join(", ")})`));
  const head = document.createElement("div");
  head.innerHTML = `<p class="conflict-head"><b>No map honours that.</b> The clash: ${said.map(escape).join(" and ")}` +
                   ` (dropping any one leaves a map).</p>`;
  const proof = document.createElement("div");
  renderWhy(proof, { ...c.explanation, text: problem.text ?? "" }, onStep);
  el.replaceChildren(head, proof);
}

// The tableau's assertions, each with a button that takes it back (onRemove(id)).
export function renderAssertions(el, assertions, onRemove) {
  if (!assertions.length) {
    el.innerHTML = `<li class="none">none yet: pick two dstates or time points, then “Same place” or “Not the same”.</li>`;
    return;
  }
  el.innerHTML = assertions.map((a) => {
    const what = a.same ? `same(${a.same.join(", ")})` : `apart(${a.apart.join(", ")})`;
    const soft = a.soft ? ` soft, cost ${a.cost}` : "";
    const held = a.held ? "" : ` <span class="broken" title="breaking it saved more than it costs">not kept</span>`;
    const note = a.note ? ` — <q>${escape(a.note)}</q>` : "";
    return `<li data-id="${escape(a.id)}"><code>${escape(what)}</code>${escape(soft)}${held}${note} ` +
           `<small>${escape(a.by)}, ${escape(new Date(a.at).toLocaleString())}</small> ` +
           `<button type="button" class="remove" data-id="${escape(a.id)}" title="Take it back: the map is solved again without it">remove</button></li>`;
  }).join("");
  el.onclick = (e) => {
    const b = e.target.closest("button.remove");
    if (b) onRemove(Number(b.dataset.id));
  };
}
