// Labelling page: pick a stream, record N frames after a countdown, choose the gesture,
// review the recording as a skeleton playback, keep or delete it; the list below shows
// every sample with its state.
import { api, isSupervisor, session } from "../api.js";
import { el } from "../dom.js";
import { clear, drawSkeleton } from "../skeleton.js";
import { on } from "../ws.js";
import { checkNumber, errorText } from "../forms.js";
import { state } from "../store.js";

const W = 480;
const H = 270;
let root = null;
let offRecording = null;
let playTimer = 0;
let current = null; // sample detail under review
let recordingId = null;
let reading = null; // the model's reading of the sample under review
let previewTimer = 0;
const GESTURE_KEY = "proxima.labelling.gesture";

const q = (sel) => root.querySelector(sel);

function status(text, cls = "") {
  if (!root) return;
  const s = q(".rec-status");
  s.textContent = text;
  s.className = `rec-status ${cls}`;
}

function play(sample) {
  clearInterval(playTimer);
  const ctx = q("canvas.review").getContext("2d");
  const n = sample.xyz.length;
  const dt = n > 1 ? Math.max(10, (1000 * (sample.times[n - 1] - sample.times[0])) / (n - 1)) : 33;
  let i = 0;
  playTimer = setInterval(() => {
    clear(ctx, W, H);
    drawSkeleton(ctx, sample.xyz[i], sample.visibility[i], W, H);
    ctx.fillStyle = "#ccc";
    ctx.font = "12px sans-serif";
    ctx.fillText(`frame ${i + 1}/${n}`, 8, H - 8);
    q("canvas.review").dataset.frame = String(i);
    i = (i + 1) % n;
  }, dt);
}

// Warn when the model's reading of the take differs from the gesture chosen for it.
function showReading() {
  const box = q(".reading");
  if (!reading || !current || reading.sample !== current.id) {
    box.textContent = "";
    return;
  }
  const chosen = q("select.gesture").value;
  const pct = (x) => `${Math.round(100 * x)}%`;
  const note = reading.padded ? ` (${reading.frames} of its ${reading.window} frames, padded)` : "";
  if (reading.gesture === chosen) {
    box.textContent = `${reading.model} reads this as ${chosen} (${pct(reading.confidence)})${note}.`;
    box.className = "reading ok";
  } else {
    box.textContent =
      `Check the gesture: ${reading.model} reads this as ${reading.gesture} (${pct(reading.confidence)}), ` +
      `not ${chosen} (${pct(reading.probs[chosen] ?? 0)})${note}. Keep it only if the pose really is ${chosen}.`;
    box.className = "reading warn";
  }
}

async function review(id) {
  current = await api(`/samples/${id}`);
  if (!root) return;
  q(".review-box").hidden = false;
  q(".review-title").textContent =
    `Sample ${current.id}: ${current.n_frames} frames of ${current.stream} for ${current.drone} (${current.status})`;
  if (current.label) q("select.gesture").value = current.label;
  q("button.keep").disabled = !isSupervisor() || current.status === "kept";
  reading = null;
  showReading();
  play(current);
  try {
    reading = await api(`/samples/${id}/reading`);
  } catch (err) {
    if (root) q(".reading").textContent = `No model reading: ${err.message}`;
    return;
  }
  if (root) showReading();
}

// The chosen stream's live skeleton, so the operator sees the pose before recording.
function preview() {
  clearInterval(previewTimer);
  previewTimer = setInterval(() => {
    if (!root) return;
    const canvas = q("canvas.preview");
    const ctx = canvas.getContext("2d");
    const s = state.streams.get(q("select.stream").value);
    clear(ctx, W / 2, H / 2);
    if (s?.pose) {
      drawSkeleton(ctx, s.pose.xyz, s.pose.visibility, W / 2, H / 2);
      canvas.dataset.poseT = String(s.pose.t);
    }
  }, 100);
}

async function decide(statusName) {
  if (!current) return;
  const label = q("select.gesture").value;
  try {
    await api(`/samples/${current.id}`, {
      method: "PATCH",
      body: { status: statusName, label: statusName === "kept" ? label : null },
    });
    if (!root) return;
    status(`Sample ${current.id} ${statusName}${statusName === "kept" ? ` as ${label}` : ""}.`, "ok");
    current.status = statusName;
    q("button.keep").disabled = statusName === "kept"; // kept once is kept
    q(".review-title").textContent = q(".review-title").textContent.replace(/\(\w+\)$/, `(${statusName})`);
    await refreshList();
  } catch (err) {
    status(err.message, "error");
  }
}

async function refreshList() {
  const rows = await api("/samples?limit=200");
  if (!root) return;
  const body = q("table.samples tbody");
  if (!rows.length) {
    body.replaceChildren(el("tr", {}, el("td", { colspan: "7", class: "muted empty-list", text: "No samples yet: record one above." })));
    return;
  }
  body.replaceChildren(
    ...rows.map((s) => {
      const tr = el(
        "tr",
        { "data-sample": String(s.id), class: `st-${s.status}` },
        el("td", { text: String(s.id) }),
        el("td", { text: new Date(s.created_at * 1000).toLocaleString() }),
        el("td", { text: s.stream }),
        el("td", { text: s.drone }),
        el("td", { class: "label", text: s.label || "—" }),
        el("td", { class: "status", text: s.status }),
        el("td", { text: String(s.n_frames) }),
      );
      tr.addEventListener("click", () => review(s.id));
      return tr;
    }),
  );
}

async function record() {
  const form = session.config.recording_form || {};
  const problems = [];
  for (const [name, input] of [["frames", q("input.frames")], ["countdown_s", q("input.countdown")]]) {
    const problem = form[name] ? checkNumber(name, form[name], input.value) : null;
    input.classList.toggle("invalid", Boolean(problem));
    if (problem) problems.push(problem);
  }
  if (problems.length) {
    status(problems.join(" "), "error");
    return;
  }
  const body = {
    stream: q("select.stream").value,
    frames: Number(q("input.frames").value),
    countdown_s: Number(q("input.countdown").value),
    label: q("select.gesture").value,
  };
  try {
    const rec = await api("/samples/recordings", { method: "POST", body });
    recordingId = rec.id;
    status(`Get ready: recording in ${body.countdown_s} s…`, "warn");
  } catch (err) {
    status(errorText(err), "error");
  }
}

function onRecording(msg) {
  if (!root || msg.recording !== recordingId) return;
  const bar = q("progress.rec-progress");
  bar.max = msg.frames_total;
  bar.value = msg.frames_done;
  if (msg.state === "countdown") status(`Get ready: ${Math.ceil(msg.countdown_s)}`, "countdown");
  else if (msg.state === "recording") status(`Recording ${msg.frames_done}/${msg.frames_total}`, "rec");
  else if (msg.state === "failed") status(`Recording failed: ${msg.detail}`, "error");
  else if (msg.state === "done") {
    status(`Recorded sample ${msg.sample_id}: review it, then keep or delete.`, "ok");
    review(msg.sample_id);
    refreshList();
  }
}

export function mount(container) {
  root = container;
  const cfg = session.config;
  const streams = el("select", { class: "stream" }, ...cfg.streams.map((s) => el("option", { value: s.name, text: `${s.name} (${s.drone})` })));
  const gestures = el("select", { class: "gesture" }, ...cfg.gestures.map((g) => el("option", { value: g, text: g })));
  const recordBtn = el("button", { class: "record", text: "Record" });
  recordBtn.addEventListener("click", record);
  const keep = el("button", { class: "keep", text: "Keep" });
  const del = el("button", { class: "delete danger", text: "Delete" });
  keep.addEventListener("click", () => decide("kept"));
  del.addEventListener("click", () => decide("deleted"));
  if (!isSupervisor()) for (const b of [recordBtn, keep, del]) b.disabled = true;
  root.append(
    el(
      "section",
      { class: "card" },
      el("h2", { text: "Record a sample" }),
      el(
        "div",
        { class: "row" },
        el("label", {}, "Stream ", streams),
        el("label", {}, "Frames ", el("input", { class: "frames", type: "number", step: "1", value: String(session.config.recording_form?.frames?.default ?? 60) })),
        el("label", {}, "Countdown (s) ", el("input", { class: "countdown", type: "number", step: "0.5", value: String(session.config.recording_form?.countdown_s?.default ?? 3) })),
        el("label", {}, "Gesture ", gestures),
        recordBtn,
      ),
      el("progress", { class: "rec-progress", max: "1", value: "0" }),
      el("p", { class: "rec-status" }),
      el("div", { class: "preview-box" }, el("h3", { text: "Live preview of the chosen stream" }), el("canvas", { class: "preview frame", width: W / 2, height: H / 2 })),
    ),
    (() => {
      const box = el(
        "section",
        { class: "card review-box" },
        el("h2", { class: "review-title" }),
        el("canvas", { class: "review frame", width: W, height: H }),
        el("p", { class: "reading" }),
        el("div", { class: "row" }, keep, del),
      );
      box.hidden = true;
      return box;
    })(),
    el(
      "section",
      { class: "card" },
      el("h2", { text: "Samples" }),
      el(
        "table",
        { class: "samples" },
        el("thead", {}, el("tr", {}, ...["id", "recorded", "stream", "drone", "gesture", "status", "frames"].map((h) => el("th", { text: h })))),
        el("tbody"),
      ),
    ),
  );
  offRecording = on("recording", onRecording);
  // The gesture chosen stays chosen (across recordings and visits to the page).
  const sel = q("select.gesture");
  const saved = sessionStorage.getItem(GESTURE_KEY);
  if (saved && [...sel.options].some((o) => o.value === saved)) sel.value = saved;
  sel.addEventListener("change", () => {
    sessionStorage.setItem(GESTURE_KEY, sel.value);
    showReading();
  });
  preview();
  for (const input of [q("input.frames"), q("input.countdown")]) {
    input.addEventListener("input", () => {
      input.classList.remove("invalid");
      if (q(".rec-status").classList.contains("error")) status("");
    });
  }
  refreshList().catch((err) => status(err.message, "error"));
}

export function unmount() {
  clearInterval(playTimer);
  clearInterval(previewTimer);
  if (offRecording) offRecording();
  root = null;
  current = null;
}
