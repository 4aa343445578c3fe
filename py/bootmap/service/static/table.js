// The tableau as a table, a row per time point, as the paper's table (6) prints it.

// Text for an HTML template, in an element or a quoted attribute: every string from the service goes
// through it (views, names, file names are what users posted), numbers too (cheap, and never wrong).
const ESCAPES = { "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" };
const escape = (s) => String(s ?? "").replace(/[&<>"']/g, (c) => ESCAPES[c]);

// Fill the table's body; onRow(t) when a row is clicked. One innerHTML: 2,000 rows in a few ms.
export function fillTable(table, rows, onRow) {
  const body = table.tBodies[0];
  body.innerHTML = rows.map((r) =>
    `<tr data-t="${escape(r.t)}" data-dstate="${escape(r.dstate)}"><td>t${escape(r.t)}</td><td>${escape(r.view)}</td>` +
    `<td>${escape(r.dstate)}</td><td>${escape(r.place ?? "")}</td><td>${escape(r.path ?? "")}</td>` +
    `<td>${escape(r.dir ?? "")}</td><td>${escape(r.action)}</td></tr>`).join("");
  body.onclick = (e) => {
    const tr = e.target.closest("tr");
    if (tr) onRow(Number(tr.dataset.t));
  };
}

// Give rows at the time points ts the class cls (and scroll the first into view when asked).
export function markRows(table, cls, ts, scroll = false) {
  for (const tr of table.querySelectorAll(`tr.${cls}`)) tr.classList.remove(cls);
  const rows = table.tBodies[0].rows;
  for (const t of ts) rows[t]?.classList.add(cls);
  if (scroll && ts.length && rows[ts[0]]) rows[ts[0]].scrollIntoView({ block: "nearest" });
}

export { escape };
