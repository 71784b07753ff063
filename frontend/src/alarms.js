// The alarm banner under the top bar, on every page: the alarms in force (critical
// first), from the store's alarm list, redrawn when an alarm arrives.
import { activeAlarms, severity } from "./store.js";
import { on } from "./ws.js";

function draw() {
  const banner = document.getElementById("alarm-banner");
  const active = activeAlarms();
  banner.hidden = active.length === 0;
  if (!active.length) return;
  const top = active[0];
  banner.className = `sev-${severity(top)}`;
  banner.textContent = `${severity(top) === "critical" ? "CRITICAL" : "WARNING"}: ${top.message}` + (active.length > 1 ? ` (+${active.length - 1} more on the Live page)` : "");
}

export function setupAlarms() {
  on("drone_alarm", draw);
  on("hello", draw);
}
