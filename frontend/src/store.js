// @ts-check
// The browser's picture of the live system, kept whatever page is shown. A stream's
// state is the server's own (`StreamLive`, reduced from the bus in api/live.py): it comes
// whole in `hello` and again in a `stream_live` message each time it changes, and is
// never recomputed here. What this module adds is what only the browser needs: the newest
// pose and thumbnail per stream to draw, the command log with each command's outcome, and
// the alarms. Pages read it and redraw what changed (`version`, `dirty`).
import { on } from "./ws.js";

/** @typedef {import("./types.gen.js").StreamLive} StreamLive */
/** @typedef {import("./types.gen.js").DroneStateEvent} DroneStateEvent */
/** @typedef {import("./types.gen.js").CommandResultEvent} CommandResultEvent */
/** @typedef {import("./types.gen.js").DroneAlarmEvent} DroneAlarmEvent */
/** @typedef {import("./types.gen.js").MessageMap["pose"]} PoseMessage */

/**
 * A stream: configuration and state from the server, and what the Live page draws.
 * @typedef {object} StreamRecord
 * @property {string} name
 * @property {string} drone
 * @property {number} priority
 * @property {string} kind
 * @property {string} uri
 * @property {boolean} driving
 * @property {StreamLive} live
 * @property {PoseMessage | null} pose the newest pose
 * @property {number} poseCount
 * @property {HTMLImageElement | null} thumb the newest thumbnail
 * @property {boolean} dirty pose or thumbnail changed since the tile was drawn
 */

/**
 * A drone: the streams that command it and its newest telemetry.
 * @typedef {object} DroneRecord
 * @property {string} name
 * @property {string[]} streams
 * @property {DroneStateEvent | null} state
 */

/** @typedef {import("./types.gen.js").CommandLogRow} CommandLogRow */
/**
 * A command-log row: one command through its life cycle (decided on the bus, then the
 * drone controller's status: pending, sent, refused, failed, ignored, done), keyed by
 * its command-log id once known. `status` "" means decided, nothing heard back yet.
 * @typedef {object} CommandRow
 * @property {number} t stream time of the gesture (wall time for console actions)
 * @property {number} ts wall time the row was made (seconds)
 * @property {string} stream
 * @property {string} drone
 * @property {string} command
 * @property {number | null} log_id
 * @property {string} status
 * @property {string} ack
 * @property {string} outcome
 * @property {string} reason
 */

const MAX_COMMANDS = 200;
const MAX_ALARMS = 50;

export const state = {
  /** @type {Map<string, StreamRecord>} */
  streams: new Map(),
  /** @type {Map<string, DroneRecord>} */
  drones: new Map(),
  /** @type {CommandRow[]} newest first */
  commands: [],
  /** @type {DroneAlarmEvent[]} newest first */
  alarms: [],
  handoverReason: "", // why the driving stream drives, or none does (the newest handover)
  version: 0, // bumped on any change outside pose/thumbnail
};

function changed() {
  state.version += 1;
}

/**
 * The stream's record, made from its configuration if new.
 * @param {{name: string, drone?: string, priority?: number, kind?: string, uri?: string}} config
 * @param {StreamLive} live
 * @returns {StreamRecord}
 */
function putStream(config, live) {
  let s = state.streams.get(config.name);
  if (!s) {
    s = {
      name: config.name,
      drone: config.drone ?? "",
      priority: config.priority ?? state.streams.size,
      kind: config.kind ?? "unknown",
      uri: config.uri ?? "",
      driving: false,
      live,
      pose: null,
      poseCount: 0,
      thumb: null,
      dirty: true,
    };
    state.streams.set(config.name, s);
  }
  s.live = live;
  return s;
}

on("hello", (msg) => {
  state.streams.clear();
  for (const s of msg.streams) putStream(s, s.live).driving = s.driving;
  state.handoverReason = msg.streams[0]?.handover_reason ?? "";
  state.drones.clear();
  for (const d of msg.drones) state.drones.set(d.name, { name: d.name, streams: d.streams, state: d.state });
  // The durable log first (times, outcomes, emergency stops: the same after a reload),
  // then what the engine decided that the log has no row for (no drone linked).
  const rows = msg.command_log.map(fromLog);
  for (const c of msg.commands) {
    if (!rows.some((r) => sameCommand(r, c.drone, c.command, c.stream, c.t))) rows.push(decided(c));
  }
  rows.sort((a, b) => b.ts - a.ts);
  state.commands = rows.slice(0, MAX_COMMANDS);
  state.alarms = msg.alarms.slice(0, MAX_ALARMS);
  changed();
});

on("stream_live", (msg) => {
  putStream({ name: msg.stream }, msg.live).driving = msg.driving;
  state.handoverReason = msg.handover_reason;
  changed();
});

on("pose", (msg) => {
  const s = state.streams.get(msg.stream); // drawn once its state has arrived
  if (!s) return;
  s.pose = msg;
  s.poseCount += 1;
  s.dirty = true;
});

on("thumbnail", (msg) => {
  const s = state.streams.get(msg.stream);
  if (!s) return;
  const img = new Image();
  img.onload = () => {
    s.thumb = img;
    s.dirty = true;
  };
  img.src = `data:image/jpeg;base64,${msg.jpeg_b64}`;
});

/** @param {CommandLogRow} r @returns {CommandRow} */
function fromLog(r) {
  return {
    t: r.gesture_t ?? 0,
    ts: r.created_at ? Date.parse(r.created_at) / 1000 : 0,
    stream: r.stream,
    drone: r.drone,
    command: r.command,
    log_id: r.id,
    status: r.status,
    ack: r.ack ?? "",
    outcome: r.outcome ?? "",
    reason: r.reason,
  };
}

/** @param {{t: number, ts: number, stream: string, drone: string, command: string}} c @returns {CommandRow} */
function decided(c) {
  return { t: c.t, ts: c.ts, stream: c.stream, drone: c.drone, command: c.command, log_id: null, status: "", ack: "", outcome: "", reason: "" };
}

/** @param {CommandRow} r @param {string} drone @param {string} command @param {string} stream @param {number | null | undefined} t */
function sameCommand(r, drone, command, stream, t) {
  return r.drone === drone && r.command === command && r.stream === stream && t != null && Math.abs(r.t - t) < 1e-6;
}

function bound() {
  if (state.commands.length > MAX_COMMANDS) state.commands.length = MAX_COMMANDS;
}

on("command", (msg) => {
  state.commands.unshift(decided(msg));
  bound();
  changed();
});

on("command_result", (msg) => {
  // One row per command: the row of its log id, else the decided command it answers
  // (same drone, command, stream and gesture time), else a new row (a console action).
  let row = msg.log_id != null ? state.commands.find((c) => c.log_id === msg.log_id) : undefined;
  row ??= state.commands.find((c) => c.log_id == null && sameCommand(c, msg.drone, msg.command, msg.stream, msg.gesture_t));
  if (!row) {
    row = { ...decided({ ...msg, t: msg.gesture_t ?? msg.t }), log_id: msg.log_id ?? null };
    state.commands.unshift(row);
    bound();
  }
  row.log_id = msg.log_id ?? row.log_id;
  row.status = msg.status;
  if (msg.ack) row.ack = msg.ack;
  if (msg.outcome) row.outcome = msg.outcome;
  if (msg.reason) row.reason = msg.reason;
  changed();
});

on("drone_state", (msg) => {
  const d = state.drones.get(msg.drone);
  if (d) d.state = msg;
  else state.drones.set(msg.drone, { name: msg.drone, streams: [], state: msg });
  changed();
});

on("drone_alarm", (msg) => {
  state.alarms.unshift(msg);
  if (state.alarms.length > MAX_ALARMS) state.alarms.length = MAX_ALARMS;
  changed();
});

/** The stream whose recognition drives the decisions, if any. */
export function drivingStream() {
  for (const s of state.streams.values()) if (s.driving) return s;
  return null;
}

/** The drone the driving stream commands, if any. */
export function drivingDrone() {
  return drivingStream()?.drone || null;
}

// Severity of alarms published without one by older links: these kinds are critical.
const CRITICAL_KINDS = new Set(["link_lost", "emergency_stop", "failsafe_landing"]);

/** @param {DroneAlarmEvent} a @returns {"critical" | "warning"} */
export function severity(a) {
  return a.severity === "critical" || CRITICAL_KINDS.has(a.kind) ? "critical" : "warning";
}

/** The alarms in force: the newest event of each drone and kind, if it is active;
 * critical first. */
export function activeAlarms() {
  const seen = new Set();
  /** @type {DroneAlarmEvent[]} */
  const out = [];
  for (const a of state.alarms) {
    const key = `${a.drone}|${a.kind}`;
    if (seen.has(key)) continue;
    seen.add(key);
    if (a.active) out.push(a);
  }
  return out.sort((a, b) => Number(severity(b) === "critical") - Number(severity(a) === "critical"));
}
