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

/**
 * A command-log row: a decided command and what became of it (`result`), or a result
 * whose command this page never saw.
 * @typedef {object} CommandRow
 * @property {number} t
 * @property {number} ts
 * @property {string} stream
 * @property {string} drone
 * @property {string} command
 * @property {CommandResultEvent | null} result
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
  state.drones.clear();
  for (const d of msg.drones) state.drones.set(d.name, { name: d.name, streams: d.streams, state: d.state });
  state.commands = msg.commands.map((c) => ({ ...c, result: null }));
  changed();
});

on("stream_live", (msg) => {
  putStream({ name: msg.stream }, msg.live).driving = msg.driving;
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

on("command", (msg) => {
  state.commands.unshift({ ...msg, result: null });
  if (state.commands.length > MAX_COMMANDS) state.commands.length = MAX_COMMANDS;
  changed();
});

on("command_result", (msg) => {
  // Attach the outcome to the newest matching command of that drone, else list it.
  const cmd = state.commands.find((c) => c.drone === msg.drone && c.command === msg.command && !c.result);
  if (cmd) cmd.result = msg;
  else state.commands.unshift({ t: msg.t, ts: msg.ts, stream: msg.stream, drone: msg.drone, command: msg.command, result: msg });
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
