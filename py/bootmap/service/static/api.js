// Requests to the service, with the user's API token when they have given one.
// The token is asked for once (when a request answers 401, or from the Token button) and kept in
// sessionStorage: this tab only, gone when it closes.

const KEY = "bootmap.token";

export function token() {
  return sessionStorage.getItem(KEY);
}

let asking = null;  // one dialog at a time: requests refused together wait for the same answer

// Ask for a token in the page's dialog; resolves true when one was given.
export function askToken(reason) {
  if (!asking) asking = showDialog(reason).finally(() => { asking = null; });
  return asking;
}

function showDialog(reason) {
  const dialog = document.getElementById("token-dialog");
  const input = document.getElementById("token-input");
  if (reason) document.getElementById("token-reason").textContent = reason;
  input.value = token() || "";
  return new Promise((resolve) => {
    dialog.addEventListener("close", () => {
      if (dialog.returnValue === "ok" && input.value.trim()) {
        sessionStorage.setItem(KEY, input.value.trim());
        resolve(true);
      } else {
        if (dialog.returnValue === "forget") sessionStorage.removeItem(KEY);
        resolve(false);
      }
    }, { once: true });
    dialog.showModal();
  });
}

export class ApiError extends Error {
  constructor(status, problem) {
    super(problem && problem.detail ? problem.detail : `HTTP ${status}`);
    this.status = status;
    this.problem = problem;
  }
}

// fetch() with Authorization: Bearer when there is a token; a 401 asks for one and tries again.
async function send(path, options = {}) {
  for (;;) {
    const headers = { ...(options.headers || {}) };
    const t = token();
    if (t) headers["Authorization"] = `Bearer ${t}`;
    const response = await fetch(path, { ...options, headers });
    if (response.status !== 401) return response;
    const problem = await response.json().catch(() => null);
    const given = await askToken(problem && problem.detail ? problem.detail : "This server needs an API token.");
    if (!given) throw new ApiError(401, problem);
  }
}

// JSON from the service. With etag: If-None-Match, and {notModified: true} on 304.
export async function getJSON(path, { etag } = {}) {
  const response = await send(path, { headers: etag ? { "If-None-Match": etag } : {} });
  if (response.status === 304) return { notModified: true, etag };
  const body = await response.json().catch(() => null);
  if (!response.ok) throw new ApiError(response.status, body);
  return { data: body, etag: response.headers.get("ETag") };
}

// A change (POST, DELETE) with a JSON body, or none; the answer's JSON. A refusal throws ApiError with
// the problem (e.g. a 409's conflict).
export async function sendJSON(method, path, body) {
  const options = { method, headers: body === undefined ? {} : { "Content-Type": "application/json" } };
  if (body !== undefined) options.body = JSON.stringify(body);
  const response = await send(path, options);
  const data = await response.json().catch(() => null);
  if (!response.ok) throw new ApiError(response.status, data);
  return { data };
}

// An image (or any file) as an object URL: <img src> cannot send the Authorization header.
export async function objectURL(path) {
  const response = await send(path);
  if (!response.ok) throw new ApiError(response.status, await response.json().catch(() => null));
  return URL.createObjectURL(await response.blob());
}
