// An explanation (GET /tableaux/{id}/why) as the page shows it: verdict, evidence, axioms, the rule
// chain from the evidence to the broken axiom (each rule with its name, file and line), alternatives.
// One HTML template with every value in it escaped (table.js's escape): the answer holds users' strings.

import { escape } from "./table.js";

const rule = (r) => `<code class="rule" title="${escape(r.level)}">${escape(r.name)}</code> ` +
                    `<span class="where">${escape(r.file)}:${escape(r.line)}</span>`;

function proofNode(node) {
  const how = node.rule ? ` — by ${rule(node.rule)}` : node.step !== null && node.step !== undefined
    ? ` — <a href="#" class="step" data-t="${escape(node.step)}">observed at t${escape(node.step)}</a>` : "";
  const premises = node.premises ?? [];  // a leaf may come without them (a conflict's proof, as solved)
  const kids = premises.length ? `<ul>${premises.map(proofNode).join("")}</ul>` : "";
  return `<li><span class="atom" title="${escape(node.atom)}">${escape(node.text)}</span>${how}${kids}</li>`;
}

export function renderWhy(el, x, onStep) {
  const ds = x.dstates.length ? ` (${x.dstates.join(", ")})` : "";
  let html = `<p class="verdict ${escape(x.verdict)}">t${escape(x.a)} and t${escape(x.b)}${escape(ds)}: ` +
             `<b>${escape(x.verdict)}</b>` +
             ` <small>levels ${escape(x.levels.join(","))}</small></p><p class="sentence">${escape(x.sentence)}</p>`;
  if (x.evidence.length) {
    html += `<h3>Evidence</h3><p class="evidence">${x.evidence.map((t) =>
      `<a href="#" class="step" data-t="${escape(t)}">t${escape(t)}</a>`).join(" ")}</p>`;
  }
  if (x.axioms.length) html += `<h3>Axioms</h3><ul class="axioms">${x.axioms.map((r) => `<li>${rule(r)}</li>`).join("")}</ul>`;
  for (const f of x.failures) {
    const merged = f.merged.map((g) => g.map((t) => `t${t}`).join("=")).join(", ");
    // the proof supposes a and b one dstate (what that merges), or, refuting a person's apart, two
    const supposing = x.supposed === "apart"
      ? `t${x.a} and t${x.b} are different dstates${merged ? ` (which makes ${merged})` : ""}` : merged;
    html += `<h3>Rule chain to ${rule(f.rule)}</h3><p class="merged">supposing ${escape(supposing)}</p>` +
            `<ul class="proof">${f.premises.map(proofNode).join("")}</ul>`;
  }
  if (x.suggestion.length) html += `<h3>To test it</h3><ul>${x.suggestion.map((s) => `<li>${escape(s)}</li>`).join("")}</ul>`;
  if (x.alternatives.length) {
    html += `<h3>Alternative minimal maps</h3><ul class="alternatives">${x.alternatives.map((a) =>
      `<li>map ${escape(a.map)}: ${escape(a.a)} and ${escape(a.b)} ${a.apart ? "apart" : "together"}</li>`).join("")}</ul>`;
  }
  html += `<details><summary>As text</summary><pre>${escape(x.text)}</pre></details>`;
  el.innerHTML = html;
  el.onclick = (e) => {
    const a = e.target.closest("a.step");
    if (a) { e.preventDefault(); onStep(Number(a.dataset.t)); }
  };
}
