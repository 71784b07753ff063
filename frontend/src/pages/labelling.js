// Labelling page: pick a stream, record N frames after a countdown, choose the gesture,
// review the recording as a skeleton playback, keep or delete it; the list below shows
// every sample with its state.
import { api, isSupervisor, session } from "../api.js";
import { el } from "../dom.js";
import { clear, drawSkeleton } from "../skeleton.js";
import { on } from "../ws.js";
import { checkNumber, errorText } from "../forms.js";

const W = 480;
const H = 270;
let root = null;
let offRecording = null;
let playTimer = 0;
let current = null; // sample detail under review
let recordingId = null;

const q = (sel) => root.querySelector(sel);

function status(text, cls = "") {
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

async function review(id) {
  current = await api(`/samples/${id}`);
  q(".review-box").hidden = false;
  q(".review-title").textContent =
    `Sample ${current.id}: ${current.n_frames} frames of ${current.stream} for ${current.drone} (${current.status})`;
  if (current.label) q("select.gesture").value = current.label;
  play(current);
}

async function decide(statusName) {
  if (!current) return;
  const label = q("select.gesture").value;
  try {
    await api(`/samples/${current.id}`, {
      method: "PATCH",
      body: { status: statusName, label: statusName === "kept" ? label : null },
    });
    status(`Sample ${current.id} ${statusName}${statusName === "kept" ? ` as ${label}` : ""}.`, "ok");
    q(".review-title").textContent = q(".review-title").textContent.replace(/\(\w+\)$/, `(${statusName})`);
    await refreshList();
  } catch (err) {
    status(err.message, "error");
  }
}

async function refreshList() {
  const rows = await api("/samples?limit=200");
  const body = q("table.samples tbody");
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
    ),
    (() => {
      const box = el(
        "section",
        { class: "card review-box" },
        el("h2", { class: "review-title" }),
        el("canvas", { class: "review frame", width: W, height: H }),
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
  if (offRecording) offRecording();
  root = null;
  current = null;
}
