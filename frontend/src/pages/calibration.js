// Calibration page: walk a new operator or camera through the gestures (prompt,
// countdown, record, the model's reading of each take with a warning when it disagrees,
// redo), then fine-tune the model that stream runs on the takes, show it before and
// after on the takes' held-out parts, and promote it for that stream only.
import { api, isSupervisor, session } from "../api.js";
import { el } from "../dom.js";
import { clear, drawSkeleton } from "../skeleton.js";
import { checkNumber, errorText } from "../forms.js";
import { state } from "../store.js";

const W = 320;
const H = 180;
const SESSION_KEY = "proxima.calibration.session";
const NUMBERS = [
  ["frames", "input.frames"],
  ["countdown_s", "input.countdown"],
  ["epochs", "input.epochs"],
];
let root = null;
let calib = null; // the session as the server last sent it
let selected = null; // the gesture prompted now
let pollTimer = 0;
let previewTimer = 0;

const q = (sel) => root.querySelector(sel);
// A model's name in models/, or the file name of one that lies elsewhere (the shipped one).
const short = (name) => (name && name.startsWith("/") ? name.split("/").pop() : name);
const pct = (x) => (x === undefined || x === null ? "—" : `${Math.round(100 * x)}%`);

function setStatus(sel, text, cls = "") {
  if (!root) return;
  const s = q(sel);
  s.textContent = text;
  s.className = `${sel.split(".").pop()} ${cls}`;
}

function busy() {
  return calib && (calib.state === "training" || calib.takes.some((t) => t.state === "recording"));
}

// While a take records or the model trains, follow the session closely.
function schedule() {
  clearTimeout(pollTimer);
  if (root && busy()) pollTimer = window.setTimeout(() => load(calib.id).catch(showError), 300);
}

function showError(err) {
  if (root) setStatus(".calib-status", errorText(err), "error");
}

async function load(id) {
  const next = await api(`/calibration/${id}`);
  if (!root) return;
  calib = next;
  sessionStorage.setItem(SESSION_KEY, calib.id);
  render();
  schedule();
}

async function startSession() {
  const form = session.config.calibration_form || {};
  const problems = [];
  for (const [name, sel] of NUMBERS) {
    const input = q(sel);
    const problem = form[name] ? checkNumber(name, form[name], input.value) : null;
    input.classList.toggle("invalid", Boolean(problem));
    if (problem) problems.push(problem);
  }
  const gestures = [...root.querySelectorAll("input.gesture-choice:checked")].map((i) => i.value);
  if (!gestures.length) problems.push("Choose at least one gesture to calibrate.");
  if (problems.length) {
    setStatus(".calib-status", problems.join(" "), "error");
    return;
  }
  try {
    calib = await api("/calibration", {
      method: "POST",
      body: {
        stream: q("select.stream").value,
        gestures,
        frames: Number(q("input.frames").value),
        countdown_s: Number(q("input.countdown").value),
        epochs: Number(q("input.epochs").value),
      },
    });
    if (!root) return;
    selected = calib.gestures[0];
    sessionStorage.setItem(SESSION_KEY, calib.id);
    setStatus(".calib-status", `Calibrating ${calib.stream} (${calib.drone}): ${calib.gestures.length} gestures.`, "ok");
    render();
  } catch (err) {
    showError(err);
  }
}

async function recordTake() {
  if (!calib || !selected) return;
  try {
    calib = await api(`/calibration/${calib.id}/takes`, { method: "POST", body: { gesture: selected } });
    render();
    schedule();
  } catch (err) {
    showError(err);
  }
}

function nextTodo() {
  if (!calib) return null;
  const order = calib.gestures;
  const at = order.indexOf(selected);
  for (let k = 1; k <= order.length; k += 1) {
    const g = order[(at + k) % order.length];
    if (calib.takes.find((t) => t.gesture === g).sample_id === null) return g;
  }
  return null;
}

async function train() {
  try {
    calib = await api(`/calibration/${calib.id}/train`, { method: "POST" });
    render();
    schedule();
  } catch (err) {
    showError(err);
  }
}

function takeStatus(take) {
  const rec = take.recording;
  if (take.state === "recording" && rec) {
    if (rec.state === "countdown") return [`Get ready: ${Math.ceil(rec.countdown_left_s ?? rec.countdown_s)}`, "countdown"];
    return [`Recording ${rec.frames_done}/${rec.frames_total}`, "rec"];
  }
  if (take.state === "failed") return [`Take failed: ${take.detail}`, "error"];
  if (take.state === "done") return [`Recorded ${take.frames} frames (sample ${take.sample_id}).`, "ok"];
  return ["Press Record when the operator is in view.", ""];
}

function readingText(take) {
  const r = take.reading;
  if (!r) return ["", ""];
  const note = r.padded ? ` (${r.frames} of its ${r.window} frames, padded)` : "";
  if (!take.warn) return [`${short(r.model)} reads this take as ${take.gesture} (${pct(r.confidence)})${note}.`, "ok"];
  return [
    `Check the take: ${short(r.model)} reads it as ${r.gesture} (${pct(r.confidence)}), not ${take.gesture} ` +
      `(${pct(r.probs[take.gesture] ?? 0)})${note}. Redo it unless the pose really is ${take.gesture}.`,
    "warn",
  ];
}

function renderWalk() {
  const box = q(".walk");
  box.hidden = !calib;
  if (!calib) return;
  if (!selected || !calib.gestures.includes(selected)) selected = nextTodo() || calib.gestures[0];
  const take = calib.takes.find((t) => t.gesture === selected);
  q(".walk-title").textContent =
    `Calibrating ${calib.stream} (${calib.drone}) · ${calib.done} of ${calib.gestures.length} takes · model ${short(calib.model)}`;
  q(".prompt-gesture").textContent = selected.replaceAll("_", " ");
  q(".prompt-gesture").dataset.gesture = selected;
  q(".prompt-description").textContent = take.description;
  const [text, cls] = takeStatus(take);
  setStatus(".take-status", text, cls);
  const bar = q("progress.take-progress");
  bar.max = calib.frames;
  bar.value = take.state === "recording" && take.recording ? take.recording.frames_done : take.state === "done" ? calib.frames : 0;
  const [rtext, rcls] = readingText(take);
  setStatus(".take-reading", rtext, rcls);
  const locked = !isSupervisor() || busy();
  const rec = q("button.record-take");
  rec.textContent = take.sample_id === null ? `Record ${selected}` : `Redo ${selected}`;
  rec.classList.toggle("redo", take.sample_id !== null);
  rec.disabled = locked;
  const next = nextTodo();
  q("button.next-take").disabled = locked || !next || take.sample_id === null;
  q("button.next-take").textContent = next ? `Next: ${next}` : "Every gesture has a take";
  q("button.train").disabled = locked || calib.done < calib.gestures.length || calib.state === "promoted";
  const list = q("ol.takes");
  list.replaceChildren(
    ...calib.takes.map((t) => {
      const cls = t.state === "recording" ? "recording" : t.sample_id === null ? (t.state === "failed" ? "failed" : "todo") : t.warn ? "warn" : "done";
      const li = el(
        "li",
        { class: `take st-${cls}${t.gesture === selected ? " current" : ""}`, "data-gesture": t.gesture },
        el("span", { class: "name", text: t.gesture }),
        el("span", { class: "mark", text: { done: " ✓", warn: " ⚠", failed: " ✗", recording: " ●", todo: "" }[cls] }),
      );
      li.addEventListener("click", () => {
        if (busy()) return;
        selected = t.gesture;
        render();
      });
      return li;
    }),
  );
}

function figureRow(name, before, after, windows) {
  const bar = (x, cls) => el("div", { class: `bar ${cls}`, style: `width: ${Math.round(100 * (x ?? 0))}%` });
  const delta = after - before;
  return el(
    "tr",
    { "data-gesture": name },
    el("td", { class: "name", text: name }),
    el("td", { class: "before", text: pct(before) }),
    el("td", { class: "after", text: pct(after) }),
    el("td", { class: `delta ${delta > 0 ? "up" : delta < 0 ? "down" : ""}`, text: `${delta >= 0 ? "+" : ""}${Math.round(100 * delta)}` }),
    el("td", { class: "bars" }, bar(before, "before"), bar(after, "after")),
    el("td", { class: "muted", text: String(windows) }),
  );
}

function renderTraining() {
  const box = q(".training-box");
  box.hidden = !calib || calib.state === "recording";
  if (box.hidden) return;
  const bar = q("progress.train-progress");
  // an ensemble's members are fine-tuned one after the other: the bar counts all their epochs
  const members = calib.members || 1;
  bar.max = calib.epochs * members;
  bar.value = Math.max(0, (calib.member || 1) - 1) * calib.epochs + calib.epoch;
  const which = members > 1 ? `model ${calib.member} of ${members}, ` : "";
  const texts = {
    training: [`Fine-tuning ${short(calib.model)} on the takes: ${which}epoch ${calib.epoch} of ${calib.epochs}${calib.loss !== null ? `, loss ${calib.loss.toFixed(3)}` : ""}…`, "warn"],
    trained: [`Trained in ${calib.seconds} s: ${calib.candidate}.`, "ok"],
    failed: [`Training failed: ${calib.detail}. The takes are kept; train again or redo a take.`, "error"],
    promoted: [`${calib.candidate} runs on ${calib.stream} (promoted by ${calib.promoted_by}).`, "ok"],
  };
  const [text, cls] = texts[calib.state] || ["", ""];
  setStatus(".train-status", text, cls);
  const figs = q(".figures");
  figs.hidden = !calib.before || !calib.after;
  if (!figs.hidden) {
    const b = calib.before;
    const a = calib.after;
    q(".figures-note").textContent =
      `Window accuracy on the held-out last ${Math.round(100 * calib.holdout_fraction)}% of each take ` +
      `(never trained on): ${short(calib.model)} before, ${calib.candidate} after.`;
    q("table.figures tbody").replaceChildren(
      ...calib.gestures.map((g) => figureRow(g, b.per_gesture[g]?.accuracy, a.per_gesture[g]?.accuracy, a.per_gesture[g]?.windows ?? 0)),
    );
    q("table.figures tfoot").replaceChildren(figureRow("overall", b.accuracy, a.accuracy, a.windows));
  }
  const promote = q("button.promote-stream");
  promote.hidden = calib.state !== "trained" && calib.state !== "promoted";
  promote.textContent = `Promote for ${calib.stream}`;
  promote.disabled = !isSupervisor() || !calib.promotion_available || calib.state === "promoted";
  promote.title = calib.promotion_available ? "" : "no live engine runs in this server";
}

function render() {
  if (!root) return;
  renderWalk();
  renderTraining();
}

// A guarded action: a confirmation naming both models, the held-out figures, and an
// override reason when the calibrated model is worse there.
function askPromote() {
  const dialog = q("dialog.promote-stream-dialog");
  const body = dialog.querySelector(".dialog-body");
  const concerns = calib.concerns || [];
  const reason = el("textarea", { class: "override-reason", rows: "2", placeholder: "why promote it anyway" });
  const confirm = el("button", { type: "button", class: "confirm-promote-stream", text: `Promote for ${calib.stream}` });
  body.replaceChildren(
    el("p", { class: "promote-question" }, "Run ", el("b", { text: calib.candidate }), ` on stream ${calib.stream} only, replacing `, el("b", { text: short(calib.model) }), " there? The other streams keep their model."),
    el("p", { class: "muted", text: `Held-out window accuracy: ${pct(calib.before.accuracy)} before, ${pct(calib.after.accuracy)} after.` }),
    ...(concerns.length
      ? [
          el("div", { class: "concerns warn" }, el("b", { text: "The calibrated model looks worse:" }), el("ul", {}, ...concerns.map((c) => el("li", { text: c })))),
          el("label", { class: "override" }, "Override reason (required to promote it anyway) ", reason),
        ]
      : []),
    el("div", { class: "row" }, confirm, el("button", { type: "button", class: "cancel", text: "Cancel" })),
    el("p", { class: "promote-result" }),
  );
  if (concerns.length) {
    confirm.disabled = true;
    confirm.classList.add("danger");
    reason.addEventListener("input", () => (confirm.disabled = !reason.value.trim()));
  }
  body.querySelector(".cancel").addEventListener("click", () => dialog.close());
  confirm.addEventListener("click", async () => {
    confirm.disabled = true;
    try {
      const res = await api(`/calibration/${calib.id}/promote`, {
        method: "POST",
        body: concerns.length ? { override_reason: reason.value.trim() } : {},
      });
      dialog.close();
      setStatus(".calib-status", `Promoted ${res.promoted} for ${res.stream} (replacing ${short(res.previous)} there).`, "ok");
      await load(calib.id);
    } catch (err) {
      const out = body.querySelector(".promote-result");
      out.textContent = errorText(err);
      out.className = "promote-result error";
      confirm.disabled = false;
    }
  });
  dialog.showModal();
}

// The chosen stream's live skeleton, so the operator can be placed before a take.
function preview() {
  clearInterval(previewTimer);
  previewTimer = window.setInterval(() => {
    if (!root) return;
    const canvas = q("canvas.preview");
    const ctx = canvas.getContext("2d");
    const s = state.streams.get(calib ? calib.stream : q("select.stream").value);
    clear(ctx, W, H);
    if (s?.pose) {
      drawSkeleton(ctx, s.pose.xyz, s.pose.visibility, W, H);
      canvas.dataset.poseT = String(s.pose.t);
    }
  }, 100);
}

export function mount(container) {
  root = container;
  const cfg = session.config;
  const form = cfg.calibration_form || {};
  const number = (cls, name, step) => el("input", { class: cls, type: "number", step, value: String(form[name]?.default ?? "") });
  const start = el("button", { class: "start-calibration", text: "Start calibration" });
  start.addEventListener("click", startSession);
  const choices = el(
    "details",
    { class: "gesture-choices" },
    el("summary", { text: "Gestures (all 13 by default)" }),
    ...cfg.gestures.map((g) => el("label", { class: "choice" }, (() => {
      const box = el("input", { type: "checkbox", class: "gesture-choice", value: g });
      box.checked = true;
      return box;
    })(), ` ${g}`)),
  );
  const recordBtn = el("button", { class: "record-take", text: "Record" });
  recordBtn.addEventListener("click", recordTake);
  const nextBtn = el("button", { class: "next-take", text: "Next" });
  nextBtn.addEventListener("click", () => {
    selected = nextTodo() || selected;
    render();
  });
  const trainBtn = el("button", { class: "train", text: "Start training" });
  trainBtn.addEventListener("click", train);
  const promoteBtn = el("button", { class: "promote-stream", text: "Promote for this stream" });
  promoteBtn.addEventListener("click", askPromote);
  if (!isSupervisor()) for (const b of [start, recordBtn, nextBtn, trainBtn, promoteBtn]) b.disabled = true;
  const walk = el(
    "section",
    { class: "card walk" },
    el("h2", { class: "walk-title" }),
    el(
      "div",
      { class: "walk-grid" },
      el(
        "div",
        { class: "prompt" },
        el("h3", { class: "prompt-gesture" }),
        el("p", { class: "prompt-description muted" }),
        el("div", { class: "row" }, recordBtn, nextBtn),
        el("progress", { class: "take-progress", max: "1", value: "0" }),
        el("p", { class: "take-status" }),
        el("p", { class: "take-reading" }),
      ),
      el("ol", { class: "takes" }),
    ),
    el("div", { class: "row" }, trainBtn),
  );
  walk.hidden = true;
  const training = el(
    "section",
    { class: "card training-box" },
    el("h2", { text: "Calibration training" }),
    el("progress", { class: "train-progress", max: "1", value: "0" }),
    el("p", { class: "train-status" }),
    (() => {
      const f = el(
        "div",
        { class: "figures" },
        el("p", { class: "figures-note muted" }),
        el(
          "table",
          { class: "figures" },
          el("thead", {}, el("tr", {}, ...["gesture", "before", "after", "change (points)", "", "windows"].map((h) => el("th", { text: h })))),
          el("tbody"),
          el("tfoot"),
        ),
      );
      f.hidden = true;
      return f;
    })(),
    promoteBtn,
  );
  training.hidden = true;
  root.append(
    el(
      "section",
      { class: "card" },
      el("h2", { text: "Calibrate a camera" }),
      el("p", { class: "muted", text: "A take of each gesture before one stream's camera; the model that stream runs is fine-tuned on the first part of each take and checked on the rest." }),
      el(
        "div",
        { class: "row" },
        el("label", {}, "Stream ", el("select", { class: "stream" }, ...cfg.streams.map((s) => el("option", { value: s.name, text: `${s.name} (${s.drone})` })))),
        el("label", {}, "Frames a take ", number("frames", "frames", "1")),
        el("label", {}, "Countdown (s) ", number("countdown", "countdown_s", "0.5")),
        el("label", {}, "Epochs ", number("epochs", "epochs", "1")),
        start,
      ),
      choices,
      el("p", { class: "calib-status" }),
      el("canvas", { class: "preview frame", width: W, height: H }),
    ),
    walk,
    training,
    el("dialog", { class: "promote-stream-dialog" }, el("h2", { text: "Promote for one stream" }), el("div", { class: "dialog-body" })),
  );
  for (const [, sel] of NUMBERS) {
    q(sel).addEventListener("input", () => q(sel).classList.remove("invalid"));
  }
  preview();
  const saved = sessionStorage.getItem(SESSION_KEY);
  if (saved) {
    load(saved).catch(() => sessionStorage.removeItem(SESSION_KEY)); // gone after a restart
  }
}

export function unmount() {
  clearTimeout(pollTimer);
  clearInterval(previewTimer);
  root = null;
  calib = null;
  selected = null;
}
