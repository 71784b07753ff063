// Emergency stop in two explicit steps: asking the server gives a confirmation id and
// stops nothing; only "Confirm" with that id before it expires stops the drone.
import { api, isSupervisor, session } from "./api.js";
import { drivingDrone, state } from "./store.js";

const $ = (sel) => document.querySelector(sel);
let pending = null; // {drone, confirmation_id, expires}
let timer = null;

function reset() {
  pending = null;
  clearInterval(timer);
  $("#estop-step1").hidden = false;
  $("#estop-step2").hidden = true;
  $("#estop-result").textContent = "";
  $("#estop-result").className = "";
}

export function openEstop(drone) {
  const dialog = $("#estop-dialog");
  reset();
  const select = $("#estop-drone");
  const names = new Set([...(session.config?.drones || []), ...state.drones.keys()]);
  select.replaceChildren(
    ...[...names].map((n) => {
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

export function setupEstop() {
  $("#estop-open").addEventListener("click", () => openEstop());
  for (const b of document.querySelectorAll("#estop-dialog .cancel")) {
    b.addEventListener("click", () => {
      reset();
      $("#estop-dialog").close();
    });
  }
  $("#estop-request").addEventListener("click", async () => {
    const drone = $("#estop-drone").value;
    $("#estop-result").textContent = "";
    try {
      const res = await api(`/drones/${encodeURIComponent(drone)}/emergency-stop`, {
        method: "POST",
      });
      pending = {
        drone,
        id: res.confirmation_id,
        expires: performance.now() + 1000 * (res.expires_in_s ?? 15),
      };
      const what = res.kind === "land" ? "It will land where it is." : res.kind ? `Action: ${res.kind}.` : "";
      $("#estop-question").textContent = `Really stop ${drone}? ${what}`;
      $("#estop-step1").hidden = true;
      $("#estop-step2").hidden = false;
      const tick = () => {
        const left = Math.max(0, Math.ceil((pending.expires - performance.now()) / 1000));
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
  });
  $("#estop-confirm").addEventListener("click", async () => {
    if (!pending) return;
    try {
      const res = await api(`/drones/${encodeURIComponent(pending.drone)}/emergency-stop/confirm`, {
        method: "POST",
        body: { confirmation_id: pending.id },
      });
      clearInterval(timer);
      $("#estop-step2").hidden = true;
      $("#estop-result").textContent = `${pending.drone}: ${res.detail || (res.ok ? "stopped" : "stop failed")}`;
      $("#estop-result").className = res.ok === false ? "error" : "ok";
      pending = null;
    } catch (err) {
      $("#estop-result").textContent = err.message;
      $("#estop-result").className = "error";
    }
  });
}
