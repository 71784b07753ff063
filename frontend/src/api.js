// Thin fetch wrapper: the session token rides as a Bearer header; errors carry the
// server's `detail` and status so pages can show them.

const TOKEN_KEY = "proxima.token";

// Every error body is the server's ErrorOut: `detail` in words, `errors` per field (422).
export class ApiError extends Error {
  constructor(status, detail, { errors = [], retryAfter = null } = {}) {
    super(typeof detail === "string" ? detail : JSON.stringify(detail));
    this.status = status;
    this.errors = errors;
    this.retryAfter = retryAfter; // seconds, on a 429 (too many failed logins)
  }
}

export const session = {
  get token() {
    return sessionStorage.getItem(TOKEN_KEY);
  },
  set token(value) {
    if (value) sessionStorage.setItem(TOKEN_KEY, value);
    else sessionStorage.removeItem(TOKEN_KEY);
  },
  user: null,
  config: null,
};

let onUnauthorized = () => {};
export function setUnauthorizedHandler(fn) {
  onUnauthorized = fn;
}

// `token` overrides the session's: logging out sends the token it has already forgotten.
export async function api(path, { method = "GET", body, token = session.token } = {}) {
  const headers = {};
  if (token) headers.Authorization = `Bearer ${token}`;
  if (body !== undefined) headers["Content-Type"] = "application/json";
  const res = await fetch(`./api${path}`, {
    method,
    headers,
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  let data = null;
  const text = await res.text();
  if (text) {
    try {
      data = JSON.parse(text);
    } catch {
      data = text;
    }
  }
  if (!res.ok) {
    if (res.status === 401 && path !== "/auth/login") onUnauthorized();
    const retry = Number.parseInt(res.headers.get("Retry-After") || "", 10);
    throw new ApiError(res.status, (data && data.detail) || res.statusText, {
      errors: (data && data.errors) || [],
      retryAfter: Number.isFinite(retry) ? retry : null,
    });
  }
  return data;
}

export function isSupervisor() {
  return session.user && session.user.role === "supervisor";
}
