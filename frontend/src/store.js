// The browser's picture of the live system, kept from WebSocket events whatever page is
// shown. Pages read it and redraw what changed (`version` counters).
import { on } from "./ws.js";

export const state = {
  streams: new Map(), // name -> stream record (see ensureStream)
  drones: new Map(), // name -> {name, streams, state: {...drone_state}}
  commands: [], // newest first: {t, stream, drone, command, wall, result}
  alarms: [], // newest first
  drivingStream: null,
  version: 0, // bumped on any change outside pose/thumbnail
  listeners: new Set(),
};

function changed() {
  state.version += 1;
  for (const fn of state.listeners) fn();
}

export function subscribe(fn) {
  state.listeners.add(fn);
  return () => state.listeners.delete(fn);
}

function ensureStream(name) {
  let s = state.streams.get(name);
  if (!s) {
    s = {
      name,
      drone: "",
      priority: state.streams.size,
      kind: "unknown",
      live: {},
      pose: null,
      poseCount: 0,
      thumb: null,
      dirty: true,
    };
    state.streams.set(name, s);
  }
  return s;
}

function ensureDrone(name) {
  let d = state.drones.get(name);
  if (!d) {
    d = { name, streams: [], state: {}, driving: false };
    state.drones.set(name, d);
  }
  return d;
}

on("hello", (msg) => {
  state.streams.clear();
  for (const s of msg.streams) {
    const rec = ensureStream(s.name);
    Object.assign(rec, {
      drone: s.drone,
      priority: s.priority,
      kind: s.kind,
      uri: s.uri,
      live: { ...s.live },
    });
    if (s.driving) state.drivingStream = s.name;
  }
  state.drones.clear();
  for (const d of msg.drones) {
    Object.assign(ensureDrone(d.name), { streams: d.streams, state: d.state || {} });
  }
  state.commands = (msg.commands || []).slice();
  changed();
});

on("pose", (msg) => {
  const s = ensureStream(msg.stream);
  s.pose = msg;
  s.poseCount += 1;
  s.live.sight = msg.sight;
  s.dirty = true;
});

on("thumbnail", (msg) => {
  const s = ensureStream(msg.stream);
  const img = new Image();
  img.onload = () => {
    s.thumb = img;
    s.dirty = true;
  };
  img.src = `data:image/jpeg;base64,${msg.jpeg_b64}`;
});

const liveFields = {
  gesture: (s, m) =>
    Object.assign(s.live, { gesture: m.gesture, gesture_confidence: m.confidence, withheld: m.withheld || [] }),
  action: (s, m) => Object.assign(s.live, { action: m.action, action_confidence: m.confidence }),
  arming: (s, m) => Object.assign(s.live, { armed: m.armed, arming_reason: m.reason }),
  stream: (s, m) => Object.assign(s.live, { state: m.state, state_detail: m.detail }),
};
for (const [type, apply] of Object.entries(liveFields)) {
  on(type, (msg) => {
    apply(ensureStream(msg.stream), msg);
    changed();
  });
}

on("handover", (msg) => {
  state.drivingStream = msg.to_stream || null;
  changed();
});

on("command", (msg) => {
  state.commands.unshift({ ...msg, result: null });
  if (state.commands.length > 200) state.commands.length = 200;
  changed();
});

on("command_result", (msg) => {
  // Attach the outcome to the newest matching command of that drone, else list it.
  const cmd = state.commands.find(
    (c) => c.drone === msg.drone && c.command === msg.command && !c.result,
  );
  if (cmd) cmd.result = msg;
  else state.commands.unshift({ ...msg, result: msg });
  changed();
});

on("drone_state", (msg) => {
  const d = ensureDrone(msg.drone);
  d.state = msg;
  changed();
});

on("drone_alarm", (msg) => {
  state.alarms.unshift(msg);
  if (state.alarms.length > 50) state.alarms.length = 50;
  changed();
});

export function drivingDrone() {
  const s = state.drivingStream && state.streams.get(state.drivingStream);
  return s ? s.drone : null;
}
