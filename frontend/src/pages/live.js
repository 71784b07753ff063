// @ts-check
// Live page: one tile per stream (frame + skeleton, raw gesture, filtered action, armed,
// stream and link state), the driving stream highlighted, drones and the command log
// beside.
import { api, isSupervisor } from "../api.js";
import { openEstop, resumeDrone } from "../estop.js";
import { el } from "../dom.js";
import { clear, drawSkeleton } from "../skeleton.js";
import { activeAlarms, drivingDrone, drivingStream, severity, state } from "../store.js";
import { on } from "../ws.js";

/** @typedef {import("../store.js").StreamRecord} StreamRecord */
/**
 * @typedef {object} Tile
 * @property {HTMLElement} el
 * @property {HTMLCanvasElement} canvas
 * @property {CanvasRenderingContext2D} ctx
 * @property {Record<string, HTMLElement>} f the tile's text fields by name
 */

const W = 384;
const H = 216;
/** @type {HTMLElement | null} */
let root = null;
let raf = 0;
let seenVersion = -1;
/** @type {Map<string, Tile>} */
const tiles = new Map();
/** @type {(() => void) | null} */
let offModel = null;
let ageTimer = 0;

/** @type {Record<string, string>} */
const KIND_TEXT = {
  camera: "camera: live video through pose estimation",
  replay: "replay: recorded landmarks (a LASER clip), no pixels",
  sim: "sim: the simulated scene's camera",
};

/** @param {number} x */
const pct = (x) => `${Math.round(x * 100)}%`;
// What the operator field says for a pose event's `sight` (see proxima.types.Sight).
/** @type {Record<string, string>} */
const SIGHT_TEXT = { full: "in view", partial: "feet out of view", none: "lost" };

/** @param {HTMLElement} container @param {string} selector */
function find(container, selector) {
  const found = container.querySelector(selector);
  if (!(found instanceof HTMLElement)) throw new Error(`no ${selector} on the Live page`);
  return found;
}

/** @param {StreamRecord} s @returns {Tile} */
function makeTile(s) {
  const canvas = el("canvas", { width: W, height: H, class: "frame" });
  /** @type {Record<string, HTMLElement>} */
  const f = {};
  /** @param {string} name @param {string} label */
  const field = (name, label) => {
    f[name] = el("span", { class: `value ${name}` });
    return el("div", { class: `field f-${name}` }, el("span", { class: "label", text: label }), f[name]);
  };
  f.title = el("span", { class: "title", text: s.name });
  f.badges = el("span", { class: "badges" });
  const tile = el(
    "article",
    { class: "tile", "data-stream": s.name },
    el("header", {}, f.title, f.badges),
    canvas,
    el(
      "div",
      { class: "fields" },
      field("gesture", "gesture"),
      field("action", "action"),
      field("armed", "control"),
      field("state", "stream"),
      field("link", "link"),
      field("sight", "operator"),
    ),
  );
  const ctx = canvas.getContext("2d");
  if (!ctx) throw new Error("no 2D canvas in this browser");
  clear(ctx, W, H);
  return { el: tile, canvas, ctx, f };
}

/** @param {StreamRecord} s @param {Tile} t */
function renderTileText(s, t) {
  const drone = state.drones.get(s.drone);
  const ds = drone?.state;
  // Gesture control is the drone controller's (drone_state), which an emergency stop
  // turns off; the engine's arming alone (StreamLive.armed) would show a stale ARMED.
  const stopped = Boolean(ds?.stopped);
  const driving = s.driving && !stopped;
  t.el.classList.toggle("driving", driving);
  t.el.classList.toggle("stopped", stopped);
  const link = ds?.link || "";
  const leader = drivingStream();
  t.f.badges.replaceChildren(
    el("span", { class: "badge b-drone", text: s.drone ? `→ ${s.drone}` : "", title: `this camera's gestures command drone ${s.drone}` }),
    el("span", {
      class: "badge b-priority",
      text: s.priority === 0 ? "main" : `#${s.priority}`,
      title: s.priority === 0
        ? "priority 0: the main camera; it drives whenever it sees the operator"
        : `priority ${s.priority}: drives only while every camera ranked above it has lost the operator`,
    }),
    el("span", { class: "badge b-kind", text: s.kind, title: KIND_TEXT[s.kind] ?? s.kind }),
    ...(driving ? [el("span", { class: "badge driving-badge", text: "DRIVING", title: `its gestures command ${s.drone} now: ${words(state.handoverReason || "operator_acquired")}` })] : []),
    ...(!driving && !stopped && leader ? [el("span", { class: "badge standby-badge", text: "STANDBY", title: `standby: takes over if ${leader.name} loses the operator (priority ${s.priority})` })] : []),
    ...(stopped ? [el("span", { class: "badge stopped-badge", text: "STOPPED", title: "emergency-stopped: a supervisor must resume it" })] : []),
  );
  const lv = s.live; // the server's StreamLive (api/live.py)
  // all_clear / not_clear differ only in the thumb: the engine does not let them become
  // the action while the camera does not see the operator's hand (control/evidence.py).
  const held = Boolean(lv.gesture) && lv.withheld.includes(lv.gesture);
  t.f.gesture.textContent = lv.gesture
    ? `${lv.gesture} ${pct(lv.gesture_confidence)}${held ? " · hand not seen: withheld" : ""}`
    : "—";
  t.f.gesture.classList.toggle("withheld", held);
  t.f.action.textContent = lv.action ? `${lv.action} ${pct(lv.action_confidence)}` : "—";
  const droneArmed = ds ? ds.gesture_control : lv.armed;
  const armed = lv.armed && droneArmed && !stopped;
  let control = "disarmed";
  if (stopped) control = "STOPPED · a supervisor must resume it";
  else if (armed) control = "ARMED";
  else if (lv.armed) control = "disarmed (the drone's gesture control is off: have_command)";
  else if (lv.arming_reason) control = `disarmed · ${lv.arming_reason}`;
  t.f.armed.textContent = control;
  t.f.armed.className = `value armed ${stopped ? "stopped" : armed ? "on" : "off"}`;
  t.f.state.textContent = lv.state || "—";
  t.f.state.className = `value state s-${lv.state || "none"}`;
  t.f.link.textContent = link || "—";
  t.f.link.className = `value link l-${link || "none"}`;
  t.f.sight.textContent = (lv.sight && SIGHT_TEXT[lv.sight]) || "—";
}

/** @param {StreamRecord} s @param {Tile} t */
function drawTile(s, t) {
  const ctx = t.ctx;
  if (s.thumb) ctx.drawImage(s.thumb, 0, 0, W, H);
  else clear(ctx, W, H);
  if (s.pose) drawSkeleton(ctx, s.pose.xyz, s.pose.visibility, W, H);
  t.canvas.dataset.poseCount = String(s.poseCount);
  t.canvas.dataset.poseT = s.pose ? String(s.pose.t) : "";
}

// Telemetry in the supervisor's terms: altitude above home (up positive; the link's
// position is NED, down positive), heading, ground speed, and how long ago the vehicle
// was last heard (its age at publication plus the time since).
/** @param {import("../store.js").DroneRecord["state"]} st */
function telemetryText(st) {
  if (!st?.position) return "no position yet";
  const alt = -st.position[2];
  const parts = [`alt ${alt.toFixed(1)} m above home`];
  if (st.attitude) parts.push(`heading ${Math.round(((st.attitude[2] * 180) / Math.PI + 360) % 360)}°`);
  if (st.velocity) parts.push(`speed ${Math.hypot(st.velocity[0], st.velocity[1]).toFixed(1)} m/s`);
  if (st.heard_age_s != null) {
    const age = st.heard_age_s + Math.max(0, Date.now() / 1000 - (/** @type {any} */ (st).ts ?? st.t));
    parts.push(`heard ${age < 10 ? age.toFixed(1) : Math.round(age)} s ago`);
  }
  return parts.join(" · ");
}

/** @param {import("../store.js").DroneRecord["state"]} st */
function targetText(st) {
  const p = st?.position;
  const tg = st?.position_target;
  if (!tg || !p) return "no target";
  const d = Math.hypot(tg[0] - p[0], tg[1] - p[1], tg[2] - p[2]);
  return `target ${tg[0].toFixed(1)} m N, ${tg[1].toFixed(1)} m E, alt ${(-tg[2]).toFixed(1)} m (${d.toFixed(1)} m away)`;
}

/** @param {HTMLElement} root */
function renderSide(root) {
  const drones = find(root, ".drones");
  const driving = drivingDrone();
  drones.replaceChildren(
    ...[...state.drones.values()].map((d) => {
      const st = d.state;
      const card = el(
        "div",
        { class: `drone ${d.name === driving && !st?.stopped ? "driving" : ""}${st?.stopped ? " stopped" : ""}`, "data-drone": d.name },
        el("b", { text: d.name }),
        el("span", { class: `badge l-${st?.link || "none"}`, text: st?.link || "no telemetry" }),
        ...(d.name === driving && !st?.stopped ? [el("span", { class: "badge driving-badge", text: "DRIVING" })] : []),
        ...(st?.stopped ? [el("span", { class: "badge stopped-badge", text: "STOPPED" })] : []),
      );
      if (isSupervisor()) {
        const b = el("button", { class: "estop small", text: "stop" });
        b.addEventListener("click", () => openEstop(d.name));
        card.append(b);
        if (st?.stopped) {
          const r = el("button", { class: "resume small", text: "resume…" });
          r.addEventListener("click", () => resumeDrone(d.name));
          card.append(r);
        }
      }
      const battery = st?.battery_pct != null ? `${Math.round(st.battery_pct)}%` : "—";
      const low = activeAlarms().find((a) => a.drone === d.name && a.kind === "battery_low");
      card.append(
        el("div", {
          text: st?.link
            ? [st.mode, st.armed ? "motors armed" : "motors disarmed", st.landed].filter(Boolean).join(" · ")
            : "no telemetry yet",
        }),
        el("div", { class: "telemetry" }, telemetryText(st), " · ", el("span", { class: `battery ${low ? `sev-${severity(low)}` : ""}`, text: `battery ${battery}` })),
        el("div", { class: "muted small-text target", text: targetText(st) }),
      );
      return card;
    }),
  );
  renderLog(root);
  const alarms = find(root, ".alarms");
  alarms.replaceChildren(
    ...activeAlarms()
      .slice(0, 5)
      .map((a) => el("div", { class: `alarm sev-${severity(a)}`, "data-kind": a.kind, text: `${severity(a).toUpperCase()} · ${a.message}` })),
  );
  // Every alarm raised or cleared since the server started, newest first.
  find(root, ".alarm-log").replaceChildren(
    ...state.alarms.slice(0, 8).map((a) =>
      el("div", { class: `alarm-line sev-${severity(a)} ${a.active ? "raised" : "cleared"}`, text: `${new Date(a.t * 1000).toLocaleTimeString()} ${a.active ? severity(a) : "cleared"}: ${a.message}` }),
    ),
  );
}

/** @param {string} x */
const words = (x) => x.replaceAll("_", " ");

// Which outcome group a row falls in, for the filter.
/** @param {import("../store.js").CommandRow} c */
function outcomeGroup(c) {
  if (!c.status) return "decided";
  if (c.status === "done" || (c.status === "sent" && c.ack === "accepted")) return "ok";
  return c.status; // pending, sent, refused, failed, ignored
}

/** @param {import("../store.js").CommandRow} c */
function stageText(c) {
  const stages = ["decided"];
  if (c.status === "pending") stages.push(c.outcome ? words(c.outcome) : "pending");
  else if (c.status === "sent" || c.status === "done") {
    if (c.status === "sent" || c.ack) stages.push("sent"); // a done arm_control sent nothing
    if (c.ack) stages.push(c.ack === "accepted" ? "acknowledged" : `ack ${words(c.ack)}`);
    if (c.status === "done") stages.push(c.outcome ? words(c.outcome) : "done");
  } else if (c.status) stages.push(c.status);
  return stages.join(" → ");
}

/** @param {HTMLElement} root */
function renderLog(root) {
  const droneSel = /** @type {HTMLSelectElement} */ (find(root, "select.log-drone"));
  const outSel = /** @type {HTMLSelectElement} */ (find(root, "select.log-outcome"));
  const names = ["", ...new Set([...state.drones.keys(), ...state.commands.map((c) => c.drone)])];
  if (droneSel.options.length !== names.length) {
    const keep = droneSel.value;
    droneSel.replaceChildren(...names.map((n) => el("option", { value: n, text: n || "all drones" })));
    droneSel.value = keep;
  }
  const rows = state.commands.filter(
    (c) => (!droneSel.value || c.drone === droneSel.value) && (!outSel.value || outcomeGroup(c) === outSel.value),
  );
  const log = find(root, ".command-log tbody");
  log.replaceChildren(
    ...rows.slice(0, 60).map((c) => {
      const when = c.ts ? new Date(c.ts * 1000).toLocaleTimeString() : "—";
      const group = outcomeGroup(c);
      const cell = el("td", { class: "outcome" }, el("div", { class: "stage", text: stageText(c) }));
      if (c.reason && group !== "ok") cell.append(el("div", { class: "reason", text: c.reason }));
      return el(
        "tr",
        { class: `st-${c.status || "decided"} g-${group}`, "data-log-id": c.log_id ?? "" },
        el("td", { class: "when", text: when }),
        el("td", { class: "who", text: c.drone || "" }),
        el("td", {}, el("div", { class: "cmd", text: c.command || "" }), el("div", { class: "muted seen-by", text: c.stream ? `seen by ${c.stream}` : "console" })),
        cell,
      );
    }),
  );
  if (!rows.length) log.replaceChildren(el("tr", {}, el("td", { colspan: "4", class: "muted", text: state.commands.length ? "No command matches the filter." : "No command yet." })));
}

// The durable log as CSV, from the server (the same filter).
/** @param {HTMLElement} root */
async function exportCsv(root) {
  const droneSel = /** @type {HTMLSelectElement} */ (find(root, "select.log-drone"));
  const outSel = /** @type {HTMLSelectElement} */ (find(root, "select.log-outcome"));
  const q = new URLSearchParams();
  if (droneSel.value) q.set("drone", droneSel.value);
  const status = { ok: "", decided: "" }[outSel.value] ?? outSel.value;
  if (status) q.set("status", status);
  const res = await fetch(`./api/commands/export.csv?${q}`, { headers: { Authorization: `Bearer ${sessionStorage.getItem("proxima.token")}` } });
  const blob = await res.blob();
  const a = el("a", { href: URL.createObjectURL(blob), download: "command-log.csv" });
  document.body.append(a);
  a.click();
  a.remove();
}

// One line on who drives and why: "front drives main (…); left is standby, priority 1",
// or that no drone is driving (no stream drives, or gesture control is disarmed).
/** @param {HTMLElement} root */
function renderWho(root) {
  const box = find(root, ".who-drives");
  const streams = [...state.streams.values()].sort((a, b) => a.priority - b.priority);
  const leader = drivingStream();
  const standby = streams.filter((s) => s !== leader).map((s) => `${s.name} is standby, priority ${s.priority}`);
  const stopped = leader && state.drones.get(leader.drone)?.state?.stopped;
  let text;
  let cls = "off";
  if (!streams.length) text = "No streams.";
  else if (!leader) text = `No drone driving: no camera sees the operator${state.handoverReason ? ` (${words(state.handoverReason)})` : ""}.`;
  else if (stopped) text = `No drone driving: ${leader.drone} is emergency-stopped.`;
  else if (!leader.live.armed) text = `No drone driving: gesture control disarmed${leader.live.arming_reason ? ` (${words(leader.live.arming_reason)})` : ""}; have_command arms it. ${leader.name} would drive ${leader.drone}.`;
  else {
    text = `${leader.name} drives ${leader.drone} (${words(state.handoverReason || "operator acquired")}).`;
    cls = "on";
  }
  if (leader && standby.length) text += ` ${standby.join("; ")}.`;
  box.textContent = text;
  box.className = `who-drives ${cls}`;
}

/** @param {HTMLElement} root */
function syncTiles(root) {
  const grid = find(root, ".tiles");
  const streams = [...state.streams.values()].sort((a, b) => a.priority - b.priority);
  for (const s of streams) {
    if (!tiles.has(s.name)) {
      const t = makeTile(s);
      tiles.set(s.name, t);
      grid.append(t.el);
    }
  }
  if (!streams.length) grid.replaceChildren(el("p", { class: "empty", text: "No streams yet." }));
  else grid.querySelector(".empty")?.remove();
}

function frame() {
  if (!root) return;
  if (seenVersion !== state.version) {
    seenVersion = state.version;
    syncTiles(root);
    for (const s of state.streams.values()) {
      const t = tiles.get(s.name);
      if (t) renderTileText(s, t);
    }
    renderSide(root);
    renderWho(root);
  }
  for (const s of state.streams.values()) {
    const t = tiles.get(s.name);
    if (!t) {
      seenVersion = -1;
      continue;
    }
    if (s.dirty) {
      s.dirty = false;
      drawTile(s, t);
    }
  }
  raf = requestAnimationFrame(frame);
}

/** @param {number | null | undefined} x */
const fixed3 = (x) => (typeof x === "number" ? x.toFixed(3) : "—");

// Which model the live engine runs: name, file date, held-out figures, who put it there.
async function showModel() {
  const box = root?.querySelector(".model-in-use");
  if (!(box instanceof HTMLElement)) return;
  try {
    const m = await api("/models/active");
    const f = m.figures;
    const when = m.since ? new Date(m.since * 1000).toLocaleString() : "";
    const how = m.action === "configured" ? "configured model" : `${m.action}d by ${m.by} at ${when}`;
    box.replaceChildren(
      el("span", { class: "label", text: "Model in use " }),
      el("b", { class: "model-name", text: m.name }),
      el("span", {
        class: "model-figures",
        text: f ? ` · accuracy ${fixed3(f.accuracy)}, wave_off ${fixed3(f.abort_recall)} (${f.set} held-out)` : "",
      }),
      el("div", {
        class: "muted",
        text: `${how}${m.modified ? ` · file of ${new Date(m.modified * 1000).toLocaleDateString()}` : ""}`,
      }),
    );
  } catch (err) {
    box.textContent = `Model in use: ${err instanceof Error ? err.message : String(err)}`;
  }
}

/** @param {HTMLElement} container */
export function mount(container) {
  root = container;
  root.append(
    el("section", { class: "main-col" }, el("div", { class: "who-drives" }), el("section", { class: "tiles" })),
    el(
      "aside",
      { class: "side" },
      el("div", { class: "model-in-use card" }),
      el("h2", { text: "Drones" }),
      el("div", { class: "alarms" }),
      el("details", { class: "alarm-history" }, el("summary", { text: "Alarm log" }), el("div", { class: "alarm-log" })),
      el("div", { class: "drones" }),
      el("h2", { text: "Command log" }),
      el(
        "div",
        { class: "row log-tools" },
        el("select", { class: "log-drone", title: "drone" }, el("option", { value: "", text: "all drones" })),
        el(
          "select",
          { class: "log-outcome", title: "outcome" },
          ...[["", "all outcomes"], ["ok", "done / acknowledged"], ["refused", "refused"], ["failed", "failed"], ["ignored", "ignored"], ["pending", "pending"], ["sent", "sent"], ["decided", "decided only"]].map(([v, t]) => el("option", { value: v, text: t })),
        ),
        el("button", { type: "button", class: "small export-csv", text: "Export CSV" }),
      ),
      el(
        "table",
        { class: "command-log" },
        el("thead", {}, el("tr", {}, ...["time", "drone", "command", "life cycle"].map((h) => el("th", { text: h })))),
        el("tbody"),
      ),
    ),
  );
  for (const sel of root.querySelectorAll(".log-tools select")) sel.addEventListener("change", () => (seenVersion = -1));
  find(root, "button.export-csv").addEventListener("click", () => root && exportCsv(root));
  tiles.clear();
  seenVersion = -1;
  for (const s of state.streams.values()) s.dirty = true;
  raf = requestAnimationFrame(frame);
  showModel();
  offModel = on("model", () => showModel());
  ageTimer = window.setInterval(() => (seenVersion = -1), 1000); // ages keep counting
}

export function unmount() {
  clearInterval(ageTimer);
  offModel?.();
  offModel = null;
  cancelAnimationFrame(raf);
  root = null;
  tiles.clear();
}
