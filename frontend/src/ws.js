// The one WebSocket to /api/ws. The token goes as the second subprotocol (browsers cannot
// set headers on a WebSocket). Reconnects with backoff; keeps delivery statistics on
// window.__proximaStats (per-stream pose counts and event -> browser latency), which the
// benchmark and the UI tests read.

const handlers = new Map(); // type -> Set(fn)
let socket = null;
let wanted = false;
let backoff = 500;
let statusListener = () => {};

const stats = {
  messages: 0,
  poses: {}, // stream -> count
  latencies: [], // seconds, newest last, bounded
  firstPose: {}, // stream -> performance.now() of the first pose
  lastPose: {}, // stream -> performance.now()
  reset() {
    this.messages = 0;
    this.poses = {};
    this.latencies = [];
    this.firstPose = {};
    this.lastPose = {};
  },
};
window.__proximaStats = stats;

export function on(type, fn) {
  if (!handlers.has(type)) handlers.set(type, new Set());
  handlers.get(type).add(fn);
  return () => handlers.get(type).delete(fn);
}

export function onStatus(fn) {
  statusListener = fn;
}

function dispatch(msg) {
  stats.messages += 1;
  if (msg.type === "pose") {
    const now = performance.now();
    stats.poses[msg.stream] = (stats.poses[msg.stream] || 0) + 1;
    if (!(msg.stream in stats.firstPose)) stats.firstPose[msg.stream] = now;
    stats.lastPose[msg.stream] = now;
    if (typeof msg.ts === "number") {
      stats.latencies.push(Date.now() / 1000 - msg.ts);
      if (stats.latencies.length > 20000) stats.latencies.splice(0, 10000);
    }
  }
  for (const key of [msg.type, "*"]) {
    const set = handlers.get(key);
    if (set) for (const fn of set) fn(msg);
  }
}

export function connect(token) {
  wanted = true;
  if (socket) return;
  const url = new URL("./api/ws", location.href);
  url.protocol = location.protocol === "https:" ? "wss:" : "ws:";
  socket = new WebSocket(url, ["proxima", token]);
  statusListener("connecting");
  socket.onopen = () => {
    backoff = 500;
    statusListener("online");
  };
  socket.onmessage = (ev) => {
    try {
      dispatch(JSON.parse(ev.data));
    } catch (err) {
      console.error("bad message", err);
    }
  };
  socket.onclose = () => {
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
