// Emergency stop in two explicit steps: asking the server gives a confirmation id and
// stops nothing; only "Confirm" with that id before it expires stops the drone. "Stop
// all" asks for every drone at once and confirms them together. On success the dialog
// closes and the result stays in the banner; a stopped drone is resumed from its card.
import { api, isSupervisor, session } from "./api.js";
import { drivingDrone, state } from "./store.js";

const $ = (sel) => document.querySelector(sel);
let pending = []; // [{drone, id, expires}]
let timer = null;

function reset() {
  pending = [];
  clearInterval(timer);
  $("#estop-step1").hidden = false;
  $("#estop-step2").hidden = true;
  $("#estop-result").textContent = "";
  $("#estop-result").className = "";
}

function droneNames() {
  return [...new Set([...(session.config?.drones || []), ...state.drones.keys()])];
}

export function openEstop(drone) {
  const dialog = $("#estop-dialog");
  reset();
  const select = $("#estop-drone");
  select.replaceChildren(
    ...droneNames().map((n) => {
      const o = document.createElement("option");
      o.value = n;
      o.textContent = n + (n === drivingDrone() ? " (driving)" : "");
      return o;
    }),
  );
  select.value = drone || drivingDrone() || select.value;
  if (!isSupervisor()) {
    $("#estop-result").textContent = "Only a supervisor can stop a drone.";
    $("#estop-result").className = "error";
  }
  dialog.showModal();
}

/** The banner under the top bar: what the last stop or resume did, until dismissed. */
export function banner(text, cls = "ok") {
  const b = $("#banner");
  b.hidden = false;
  b.className = `banner ${cls}`;
  b.querySelector(".banner-text").textContent = text;
}

async function ask(drones) {
  $("#estop-result").textContent = "";
  try {
    const answers = await Promise.all(
      drones.map((d) => api(`/drones/${encodeURIComponent(d)}/emergency-stop`, { method: "POST" })),
    );
    pending = answers.map((res, i) => ({
      drone: drones[i],
      id: res.confirmation_id,
      kind: res.kind,
      expires: performance.now() + 1000 * (res.expires_in_s ?? 15),
    }));
    const kind = pending[0]?.kind;
    const what = kind === "land" ? (drones.length > 1 ? "They will land where they are." : "It will land where it is.") : kind ? `Action: ${kind}.` : "";
    $("#estop-question").textContent = `Really stop ${drones.join(", ")}? ${what}`;
    $("#estop-step1").hidden = true;
    $("#estop-step2").hidden = false;
    const tick = () => {
      const left = Math.max(0, Math.ceil((Math.min(...pending.map((p) => p.expires)) - performance.now()) / 1000));
      $("#estop-expiry").textContent = left;
      if (left === 0) {
        clearInterval(timer);
        $("#estop-result").textContent = "Confirmation expired; ask again.";
        $("#estop-result").className = "error";
        $("#estop-step1").hidden = false;
        $("#estop-step2").hidden = true;
      }
    };
    tick();
    timer = setInterval(tick, 250);
  } catch (err) {
    $("#estop-result").textContent = err.message;
    $("#estop-result").className = "error";
  }
}

export async function resumeDrone(drone) {
  const ok = window.confirm(
    `Resume ${drone}? Gesture control may be armed again by the operator's have_command. ` +
      "Take off again with the drone's own controls.",
  );
  if (!ok) return;
  try {
    const res = await api(`/drones/${encodeURIComponent(drone)}/resume`, { method: "POST" });
    banner(`${drone}: ${res.detail}`, "ok");
  } catch (err) {
    banner(`${drone}: ${err.message}`, "error");
  }
}

export function setupEstop() {
  $("#estop-open").addEventListener("click", () => openEstop());
  $("#banner .dismiss").addEventListener("click", () => ($("#banner").hidden = true));
  for (const b of document.querySelectorAll("#estop-dialog .cancel")) {
    b.addEventListener("click", () => {
      reset();
      $("#estop-dialog").close();
    });
  }
  $("#estop-request").addEventListener("click", () => ask([$("#estop-drone").value]));
  $("#estop-request-all").addEventListener("click", () => ask(droneNames()));
  $("#estop-confirm").addEventListener("click", async () => {
    if (!pending.length) return;
    const results = await Promise.all(
      pending.map((p) =>
        api(`/drones/${encodeURIComponent(p.drone)}/emergency-stop/confirm`, {
          method: "POST",
          body: { confirmation_id: p.id },
        }).then(
          (res) => ({ drone: p.drone, ok: res.ok !== false, text: res.detail || (res.ok ? "stopped" : "stop failed") }),
          (err) => ({ drone: p.drone, ok: false, text: err.message }),
        ),
      ),
    );
    clearInterval(timer);
    pending = [];
    const text = results.map((r) => `${r.drone}: emergency stop ${r.ok ? "sent" : "FAILED"} (${r.text})`).join("; ");
    const allOk = results.every((r) => r.ok);
    banner(`${text}. Resume a stopped drone from its card.`, allOk ? "ok" : "error");
    if (allOk) {
      reset();
      $("#estop-dialog").close();
    } else {
      $("#estop-result").textContent = text;
      $("#estop-result").className = "error";
      $("#estop-step1").hidden = false;
      $("#estop-step2").hidden = true;
    }
  });
}
