// @ts-check
// The one WebSocket to /api/ws. The token goes as the second subprotocol (browsers cannot
// set headers on a WebSocket). Reconnects with backoff; keeps delivery statistics on
// window.__proximaStats (per-stream pose counts and event -> browser latency), which the
// benchmark and the UI tests read. Messages are typed by types.gen.js (generated from the
// backend: `python -m proxima.api.typegen`); `on` refuses a type the server never sends.
import { MESSAGE_TYPES } from "./types.gen.js";

/** @typedef {import("./types.gen.js").MessageMap} MessageMap */
/** @typedef {import("./types.gen.js").Message} Message */

/** @type {Map<string, Set<(msg: any) => void>>} type -> handlers */
const handlers = new Map();
/** @type {WebSocket | null} */
let socket = null;
let wanted = false;
let backoff = 500;
/** @type {(status: "connecting" | "online" | "offline") => void} */
let statusListener = () => {};

const stats = {
  messages: 0,
  /** @type {Record<string, number>} stream -> pose messages */
  poses: {},
  /** @type {number[]} seconds, newest last, bounded */
  latencies: [],
  /** @type {Record<string, number>} stream -> performance.now() of the first pose */
  firstPose: {},
  /** @type {Record<string, number>} stream -> performance.now() of the newest pose */
  lastPose: {},
  reset() {
    this.messages = 0;
    this.poses = {};
    this.latencies = [];
    this.firstPose = {};
    this.lastPose = {};
  },
};
/** @type {any} */ (window).__proximaStats = stats;

/**
 * Call `fn` with every message of `type`; returns the function that stops it.
 * @template {keyof MessageMap} K
 * @param {K} type
 * @param {(msg: MessageMap[K]) => void} fn
 * @returns {() => void}
 */
export function on(type, fn) {
  if (!MESSAGE_TYPES.includes(type)) throw new Error(`the server sends no "${type}" messages`);
  let set = handlers.get(type);
  if (!set) handlers.set(type, (set = new Set()));
  set.add(fn);
  return () => set.delete(fn);
}

/** @param {(status: "connecting" | "online" | "offline") => void} fn */
export function onStatus(fn) {
  statusListener = fn;
}

/** @param {Message} msg */
function dispatch(msg) {
  stats.messages += 1;
  if (msg.type === "pose") {
    const now = performance.now();
    stats.poses[msg.stream] = (stats.poses[msg.stream] || 0) + 1;
    if (!(msg.stream in stats.firstPose)) stats.firstPose[msg.stream] = now;
    stats.lastPose[msg.stream] = now;
    stats.latencies.push(Date.now() / 1000 - msg.ts);
    if (stats.latencies.length > 20000) stats.latencies.splice(0, 10000);
  }
  const set = handlers.get(msg.type);
  if (set) for (const fn of set) fn(msg);
}

/** @param {string} token */
export function connect(token) {
  wanted = true;
  if (socket) return;
  const url = new URL("./api/ws", location.href);
  url.protocol = location.protocol === "https:" ? "wss:" : "ws:";
  const ws = new WebSocket(url, ["proxima", token]);
  socket = ws;
  statusListener("connecting");
  ws.onopen = () => {
    backoff = 500;
    statusListener("online");
  };
  ws.onmessage = (ev) => {
    try {
      dispatch(JSON.parse(ev.data));
    } catch (err) {
      console.error("bad message", err);
    }
  };
  ws.onclose = () => {
    socket = null;
    statusListener("offline");
    if (wanted) {
      setTimeout(() => wanted && connect(token), backoff);
      backoff = Math.min(backoff * 2, 8000);
    }
  };
}

export function disconnect() {
  wanted = false;
  if (socket) socket.close();
  socket = null;
}
