// 3D page: the viser scene (drones with trails, the operator, the geofence, the active
// drone highlighted), served through the console at /viser/ (the viser server itself
// listens on 127.0.0.1 only) and embedded here. One login covers both: the page and its
// WebSocket carry the session in the `proxima_view` cookie, refreshed here first so it
// belongs to this tab's session.
import { api, session } from "../api.js";

export async function mount(root) {
  const url = session.config.view_url;
  if (!url) {
    const p = document.createElement("p");
    p.className = "empty";
    p.textContent = "The 3D view is not running in this server (server.viser_enabled).";
    root.append(p);
    return;
  }
  try {
    await api("/auth/view-cookie", { method: "POST" });
  } catch (err) {
    const p = document.createElement("p");
    p.className = "error";
    p.textContent = `The 3D view cannot be opened: ${err.message}`;
    root.append(p);
    return;
  }
  const frame = document.createElement("iframe");
  frame.className = "viser";
  frame.title = "3D view";
  frame.src = url;
  const link = document.createElement("a");
  link.href = url;
  link.target = "_blank";
  link.rel = "noopener";
  link.textContent = "open in its own tab";
  root.append(frame, link);
}

export function unmount() {}
