// 3D page: the viser scene (drones with trails, the operator, the geofence, the active
// drone highlighted), served by its own server and embedded here.
import { session } from "../api.js";

export function mount(root) {
  const port = session.config.viz_port;
  if (!port) {
    const p = document.createElement("p");
    p.className = "empty";
    p.textContent = "The 3D view is not running in this server (server.viser_enabled).";
    root.append(p);
    return;
  }
  const frame = document.createElement("iframe");
  frame.className = "viser";
  frame.title = "3D view";
  frame.src = `${location.protocol}//${location.hostname}:${port}/`;
  const link = document.createElement("a");
  link.href = frame.src;
  link.target = "_blank";
  link.textContent = "open in its own tab";
  root.append(frame, link);
}

export function unmount() {}
