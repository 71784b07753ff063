// Boot: log in (or restore the session), open the WebSocket, route between pages.
import "./style.css";
import { api, ApiError, isSupervisor, session, setUnauthorizedHandler } from "./api.js";
import { connect, disconnect, onStatus } from "./ws.js";
import { setupEstop } from "./estop.js";
import { setupAlarms } from "./alarms.js";
import * as live from "./pages/live.js";
import * as training from "./pages/training.js";
import * as labelling from "./pages/labelling.js";
import * as calibration from "./pages/calibration.js";
import * as viz from "./pages/viz.js";

const pages = { live, training, labelling, calibration, "3d": viz };
let current = null;
const $ = (sel) => document.querySelector(sel);

function showLogin(step = "login") {
  disconnect();
  $("#topbar").hidden = true;
  $("#app").replaceChildren();
  current = null;
  $("#login").hidden = false;
  $("#login-form").hidden = step !== "login";
  $("#password-form").hidden = step !== "password";
}

async function start() {
  session.user = await api("/auth/me");
  if (session.user.must_change_password) {
    showLogin("password");
    return;
  }
  session.config = await api("/config");
  $("#login").hidden = true;
  $("#topbar").hidden = false;
  $("#whoami").textContent = `${session.user.username} (${session.user.role})`;
  document.body.classList.toggle("viewer", !isSupervisor());
  connect(session.token);
  route();
}

function route() {
  if (!session.config) return;
  const name = (location.hash.replace(/^#\//, "") || "live").split("?")[0];
  const page = pages[name] || live;
  if (current) current.unmount();
  const el = document.createElement("div");
  el.className = `page page-${name}`;
  $("#app").replaceChildren(el);
  current = page;
  page.mount(el);
  for (const a of document.querySelectorAll("nav a")) {
    a.classList.toggle("active", a.dataset.page === name);
  }
}

// After too many failed logins the server answers 429 with Retry-After: say so, count
// down, and keep the button disabled until a login may be tried again.
let throttleTimer = null;
function showThrottled(seconds) {
  const button = $("#login-form button[type=submit]");
  const error = $("#login-error");
  clearInterval(throttleTimer);
  let left = seconds;
  const tick = () => {
    if (left <= 0) {
      clearInterval(throttleTimer);
      button.disabled = false;
      error.textContent = "";
      return;
    }
    button.disabled = true;
    error.textContent = `Too many failed logins: try again in ${left} s.`;
    left -= 1;
  };
  tick();
  throttleTimer = setInterval(tick, 1000);
}

$("#login-form").addEventListener("submit", async (ev) => {
  ev.preventDefault();
  const form = new FormData(ev.target);
  $("#login-error").textContent = "";
  try {
    const res = await api("/auth/login", {
      method: "POST",
      body: { username: form.get("username"), password: form.get("password") },
    });
    session.token = res.token;
    ev.target.reset();
    await start();
  } catch (err) {
    if (err instanceof ApiError && err.status === 429 && err.retryAfter) {
      showThrottled(err.retryAfter);
      return;
    }
    $("#login-error").textContent = err instanceof ApiError ? err.message : String(err);
  }
});

$("#password-form").addEventListener("submit", async (ev) => {
  ev.preventDefault();
  const form = new FormData(ev.target);
  $("#password-error").textContent = "";
  try {
    await api("/auth/password", {
      method: "POST",
      body: { old_password: form.get("old_password"), new_password: form.get("new_password") },
    });
    ev.target.reset();
    await start();
  } catch (err) {
    $("#password-error").textContent = err.message;
  }
});

// Forget the token before telling the server: a reload while the request is on its way
// must land on the login form, not restore the session being closed.
$("#logout").addEventListener("click", async () => {
  const token = session.token;
  session.token = null;
  showLogin();
  try {
    await api("/auth/logout", { method: "POST", token });
  } catch {
    /* already gone */
  }
});

onStatus((s) => {
  const el = $("#conn");
  el.textContent = s;
  el.className = `badge ${s === "online" ? "ok" : s === "connecting" ? "warn" : "off"}`;
});

setUnauthorizedHandler(() => {
  session.token = null;
  showLogin();
});

window.addEventListener("hashchange", route);
setupEstop();
setupAlarms();

if (session.token) {
  start().catch(() => {
    session.token = null;
    showLogin();
  });
} else {
  showLogin();
}
