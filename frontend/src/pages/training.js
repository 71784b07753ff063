// Training page: start a federated run with its parameters, watch loss and accuracy per
// round (global model and each drone) grow live, browse past runs, promote a model.
import {
  Chart,
  Legend,
  LinearScale,
  LineController,
  LineElement,
  PointElement,
  Tooltip,
} from "chart.js";
import { api, isSupervisor, session } from "../api.js";
import { el } from "../dom.js";
import { on } from "../ws.js";
import { checkNumber, errorText } from "../forms.js";

Chart.register(LineController, LineElement, PointElement, LinearScale, Legend, Tooltip);

const COLORS = ["#4fc3f7", "#ffb74d", "#81c784", "#e57373", "#ba68c8", "#fff176", "#90a4ae"];
let root = null;
let charts = {};
let selected = null; // run id shown in the charts
let offs = [];

// A request can answer after the page was left (unmount sets root to null), so every
// continuation after an await checks root before it touches the page.
const q = (sel) => root.querySelector(sel);

function makeChart(canvas, title, yMax) {
  return new Chart(canvas, {
    type: "line",
    data: { datasets: [] },
    options: {
      animation: false,
      responsive: true,
      maintainAspectRatio: false,
      plugins: { legend: { labels: { color: "#ddd" } }, title: { display: false, text: title } },
      scales: {
        x: {
          type: "linear",
          title: { display: true, text: "round", color: "#aaa" },
          ticks: { color: "#aaa", stepSize: 1, precision: 0 },
        },
        y: { title: { display: true, text: title, color: "#aaa" }, ticks: { color: "#aaa" }, min: 0, max: yMax },
      },
    },
  });
}

function series(chart, name, i) {
  let ds = chart.data.datasets.find((d) => d.label === name);
  if (!ds) {
    const color = COLORS[i % COLORS.length];
    ds = {
      label: name,
      data: [],
      borderColor: color,
      backgroundColor: color,
      borderWidth: name === "global" ? 3 : 1.5,
      borderDash: name === "global" ? [] : [4, 3],
      tension: 0.1,
    };
    chart.data.datasets.push(ds);
  }
  return ds;
}

// A round, from GET /training/runs/{id} or a `training_round` message: {round,
// global_accuracy, global_loss, clients: [{drone, phase, status, loss, accuracy, ...}]}.
function clientsOf(r) {
  // Each drone's own training result of the round (not a failed or federated-evaluation row).
  return (r.clients || [])
    .filter((x) => (x.phase ?? "train") === "train" && (x.status ?? "ok") === "ok")
    .map((x) => [x.drone, x]);
}

function addRound(r) {
  const round = Number(r.round);
  const put = (chart, name, i, value) => {
    if (typeof value !== "number" || !Number.isFinite(value)) return;
    const ds = series(chart, name, i);
    ds.data = ds.data.filter((p) => p.x !== round).concat([{ x: round, y: value }]);
    ds.data.sort((a, b) => a.x - b.x);
  };
  put(charts.accuracy, "global", 0, r.global_accuracy);
  put(charts.loss, "global", 0, r.global_loss);
  clientsOf(r).forEach(([name, m], i) => {
    put(charts.accuracy, name, i + 1, m.accuracy);
    put(charts.loss, name, i + 1, m.loss ?? m.train_loss);
  });
  for (const chart of Object.values(charts)) chart.update();
  q(".chart-points").textContent = String(charts.accuracy.data.datasets.reduce((n, d) => n + d.data.length, 0));
}

function resetCharts(title) {
  for (const chart of Object.values(charts)) {
    chart.data.datasets = [];
    chart.update();
  }
  q(".run-title").textContent = title;
  q(".chart-points").textContent = "0";
}

async function showRun(id) {
  selected = id;
  const run = await api(`/training/runs/${encodeURIComponent(id)}`);
  if (!root) return;
  resetCharts(`Run ${id}: ${run.status || ""}`);
  for (const r of run.rounds || []) addRound(r);
}

// A run's wall time as m:ss (h:mm:ss past an hour); "running" until it has finished.
function duration(r) {
  if (!r.started_at) return "";
  if (!r.finished_at) return r.status === "running" ? "running" : "";
  const s = Math.max(0, Math.round(r.finished_at - r.started_at));
  const hh = Math.floor(s / 3600);
  const mm = Math.floor((s % 3600) / 60);
  const ss = String(s % 60).padStart(2, "0");
  return hh ? `${hh}:${String(mm).padStart(2, "0")}:${ss}` : `${mm}:${ss}`;
}

async function refreshRuns() {
  const runs = await api("/training/runs");
  if (!root) return;
  if (selected === null && runs.length) showRun(runs[0].id).catch(showError);
  q("table.runs tbody").replaceChildren(
    ...runs.map((r) => {
      const tr = el(
        "tr",
        { "data-run": r.id },
        el("td", { text: String(r.id) }),
        el("td", { class: "status", text: r.status || "" }),
        el("td", { text: r.started_at ? new Date(r.started_at * 1000).toLocaleString() : "" }),
        el("td", { class: "duration", text: duration(r) }),
        el("td", { text: String(r.params?.rounds ?? r.rounds_total ?? "") }),
        el("td", { text: typeof r.final_accuracy === "number" ? r.final_accuracy.toFixed(3) : "" }),
        el("td", { text: r.checkpoint ? r.checkpoint.split("/").pop() : "" }),
      );
      tr.addEventListener("click", () => showRun(r.id));
      return tr;
    }),
  );
}

const fmt = (x) => (typeof x === "number" ? x.toFixed(3) : "—");
const modelPath = (name) => name.split("/").map(encodeURIComponent).join("/");

function fillFigures(tr, f) {
  tr.querySelector(".acc").textContent = f ? fmt(f.accuracy) : "…";
  tr.querySelector(".abort").textContent = f ? fmt(f.abort_recall) : "…";
  if (f) tr.querySelector(".acc").title = `window accuracy on ${f.set_description}`;
}

// Figures are computed on the server once per checkpoint (a few seconds each): rows
// without them are filled in one at a time after the table is drawn.
async function evaluateMissing(rows) {
  for (const [tr, m] of rows) {
    if (!root) return;
    try {
      const cmp = await api(`/models/${modelPath(m.name)}/evaluation`);
      fillFigures(tr, cmp.candidate.figures);
    } catch (err) {
      tr.querySelector(".acc").textContent = "not evaluable";
      tr.querySelector(".acc").title = err.message;
      tr.querySelector(".abort").textContent = "";
    }
  }
}

async function refreshModels() {
  const res = await api("/models");
  if (!root) return;
  const missing = [];
  q("table.models tbody").replaceChildren(
    ...res.models.map((m) => {
      const btn = el("button", { class: "promote small", text: m.active ? "in use" : "promote…" });
      btn.disabled = m.active || !isSupervisor() || !res.promotion_available;
      btn.addEventListener("click", () => askPromote(m.name));
      const tr = el(
        "tr",
        { "data-model": m.name, class: m.active ? "active-model" : "" },
        el("td", { class: "name", text: m.name }),
        el("td", { text: new Date(m.modified * 1000).toLocaleString() }),
        el("td", { class: "acc" }),
        el("td", { class: "abort" }),
        el("td", { text: `${Math.round(m.size_bytes / 1024)} KiB` }),
        el("td", {}, btn),
      );
      fillFigures(tr, m.figures);
      if (!m.figures) missing.push([tr, m]);
      return tr;
    }),
  );
  refreshHistory().catch(showError);
  evaluateMissing(missing);
}

async function refreshHistory() {
  const { history } = await api("/models/history");
  if (!root) return;
  q("table.history tbody").replaceChildren(
    ...(history.length
      ? history.map((h) =>
          el(
            "tr",
            {},
            el("td", { text: new Date(h.ts * 1000).toLocaleString() }),
            el("td", { text: h.action }),
            el("td", { text: h.checkpoint }),
            el("td", { text: h.previous || "—" }),
            el("td", { text: fmt(h.figures?.accuracy) }),
            el("td", { text: h.by }),
            el("td", { text: h.override_reason || "" }),
          ),
        )
      : [el("tr", {}, el("td", { colspan: "7", class: "muted", text: "No model promoted yet: the live engine runs the configured one." }))]),
  );
  const rb = q("button.rollback");
  rb.disabled = !history.length || !history[0].previous || !isSupervisor();
  rb.textContent = history.length && history[0].previous ? `Roll back to ${history[0].previous}` : "Roll back";
}

async function rollback() {
  if (!window.confirm(`${q("button.rollback").textContent}? The live engine switches at once.`)) return;
  try {
    const res = await api("/models/rollback", { method: "POST" });
    setStatus(`Rolled back: the live engine runs ${res.promoted} again.`, "ok");
  } catch (err) {
    showError(err);
  }
  refreshModels().catch(showError);
}

// Promotion is a guarded action: the candidate's figures beside the model in use's on
// the held-out set, a confirmation naming both, and an override reason when it is worse.
async function askPromote(name) {
  const dialog = document.getElementById("promote-dialog");
  const body = dialog.querySelector(".promote-body");
  body.replaceChildren(el("p", { class: "muted", text: `Evaluating ${name} and the model in use…` }));
  dialog.showModal();
  let cmp;
  try {
    cmp = await api(`/models/${modelPath(name)}/evaluation`);
  } catch (err) {
    body.replaceChildren(el("p", { class: "error", text: err.message }));
    return;
  }
  const row = (label, m) =>
    el("tr", {}, el("td", { text: label }), el("td", { class: "name", text: m ? m.name : "—" }),
      el("td", { class: "acc", text: fmt(m?.figures?.accuracy) }),
      el("td", { text: fmt(m?.figures?.clip_accuracy) }),
      el("td", { class: "abort", text: fmt(m?.figures?.abort_recall) }));
  const reason = el("textarea", { class: "override-reason", rows: "2", placeholder: "why promote it anyway" });
  const confirm = el("button", { type: "button", class: "confirm-promote", text: `Promote ${name}` });
  const concerns = cmp.concerns || [];
  body.replaceChildren(
    el("p", {}, `Promote `, el("b", { text: name }), ` into the live engine, replacing `, el("b", { text: cmp.active ? cmp.active.name : "the configured model" }), "?"),
    el("table", { class: "compare" },
      el("thead", {}, el("tr", {}, ...["", "model", "accuracy", "clip accuracy", "wave_off recall"].map((h) => el("th", { text: h })))),
      el("tbody", {}, row("candidate", cmp.candidate), row("in use", cmp.active))),
    el("p", { class: "muted", text: `Held-out set: ${cmp.set_description}.` }),
    ...(concerns.length
      ? [
          el("div", { class: "concerns warn" }, el("b", { text: "This model looks worse:" }), el("ul", {}, ...concerns.map((c) => el("li", { text: c })))),
          el("label", { class: "override" }, "Override reason (required to promote it anyway) ", reason),
        ]
      : [el("p", { class: "ok", text: "Not worse than the model in use on this set." })]),
    el("div", { class: "row" }, confirm, el("button", { type: "button", class: "cancel", text: "Cancel" })),
    el("p", { class: "promote-result" }),
  );
  if (concerns.length) {
    confirm.disabled = true;
    confirm.classList.add("danger");
    confirm.textContent = `Override and promote ${name}`;
    reason.addEventListener("input", () => (confirm.disabled = !reason.value.trim()));
  }
  body.querySelector(".cancel").addEventListener("click", () => dialog.close());
  confirm.addEventListener("click", async () => {
    confirm.disabled = true;
    try {
      const res = await api(`/models/${modelPath(name)}/promote`, {
        method: "POST",
        body: concerns.length ? { override_reason: reason.value.trim() } : {},
      });
      dialog.close();
      setStatus(`Promoted ${name} to the live engine (replacing ${res.previous || "the configured model"}).`, "ok");
    } catch (err) {
      body.querySelector(".promote-result").textContent = err.message;
      body.querySelector(".promote-result").className = "promote-result error";
      confirm.disabled = false;
    }
    refreshModels().catch(showError);
  });
}

function setStatus(text, cls = "") {
  if (!root) return;
  const s = q(".train-status");
  s.textContent = text;
  s.className = `train-status ${cls}`;
}

// A refresh that failed says so on the page (its promise is not left unhandled).
const showError = (err) => setStatus(err.message, "error");

// The form is drawn from `training_form` in /api/config: per field, the type, bounds and
// choices of the backend's FLConfig and the runner's default, so it cannot drift from
// what POST /training/runs accepts.
const LABELS = { include_samples: "with labelled samples" };

function formFields() {
  return Object.entries(session.config.training_form || {});
}

async function startRun(ev) {
  ev.preventDefault();
  const f = new FormData(ev.target);
  const body = {};
  const problems = [];
  for (const [name, spec] of formFields()) {
    if (spec.type === "boolean") body[name] = f.get(name) === "on";
    else if (spec.enum) body[name] = f.get(name);
    else {
      const problem = checkNumber(name, spec, f.get(name));
      ev.target.querySelector(`[name=${name}]`)?.classList.toggle("invalid", Boolean(problem));
      if (problem) problems.push(problem);
      body[name] = Number(f.get(name));
    }
  }
  if (problems.length) {
    setStatus(problems.join(" "), "error");
    return;
  }
  try {
    const res = await api("/training/runs", { method: "POST", body });
    if (!root) return;
    setStatus(`Run ${res.id} started.`, "ok");
    selected = res.id;
    resetCharts(`Run ${res.id}: starting`);
    refreshRuns().catch(showError);
  } catch (err) {
    setStatus(`${err.status === 403 ? "Forbidden: " : ""}${errorText(err)}`, "error");
  }
}

function field(name, spec) {
  if (spec.type === "boolean") {
    const box = el("input", { name, type: "checkbox" });
    box.checked = Boolean(spec.default);
    return el("label", {}, box, ` ${LABELS[name] ?? name.replace("_", " ")}`);
  }
  if (spec.enum) {
    const select = el("select", { name }, ...spec.enum.map((o) => el("option", { value: o, text: o })));
    select.value = spec.default;
    return el("label", {}, `${name} `, select);
  }
  const attrs = { name, type: "number", value: String(spec.default), step: spec.type === "integer" ? "1" : "any" };
  const min = spec.minimum ?? spec.exclusiveMinimum;
  const max = spec.maximum ?? spec.exclusiveMaximum;
  if (min !== undefined) attrs.min = String(min);
  if (max !== undefined) attrs.max = String(max);
  return el("label", {}, `${name.replace("_", " ")} `, el("input", attrs));
}

export function mount(container) {
  root = container;
  const form = el(
    "form",
    { class: "card start-run", novalidate: "" },
    el("h2", { text: "Start a federated run" }),
    el(
      "div",
      { class: "row wrap" },
      ...formFields().map(([name, spec]) => field(name, spec)),
      el("button", { type: "submit", class: "start", text: "Start run" }),
    ),
    el("p", { class: "train-status" }),
  );
  form.addEventListener("submit", startRun);
  // A message about the form goes once it is being corrected.
  form.addEventListener("input", (ev) => {
    ev.target.classList?.remove("invalid");
    if (q(".train-status").classList.contains("error")) setStatus("");
  });
  root.append(
    form,
    el(
      "section",
      { class: "card" },
      el("h2", {}, el("span", { class: "run-title", text: "No run selected" })),
      el("p", { class: "muted" }, "points: ", el("span", { class: "chart-points", text: "0" })),
      el(
        "div",
        { class: "charts" },
        el("div", { class: "chart" }, el("h3", { text: "Loss per round" }), el("div", { class: "chart-box" }, el("canvas", { class: "loss" }))),
        el("div", { class: "chart" }, el("h3", { text: "Accuracy per round" }), el("div", { class: "chart-box" }, el("canvas", { class: "accuracy" }))),
      ),
    ),
    el(
      "section",
      { class: "card" },
      el("h2", { text: "Past runs" }),
      el("table", { class: "runs" }, el("thead", {}, el("tr", {}, ...["id", "status", "started", "duration", "rounds", "accuracy", "checkpoint"].map((h) => el("th", { text: h })))), el("tbody")),
    ),
    el(
      "section",
      { class: "card" },
      el("h2", { text: "Models" }),
      el("p", { class: "muted", text: "Accuracy and wave_off (abort) recall on the held-out synthetic set, which no model here trained on." }),
      el("table", { class: "models" }, el("thead", {}, el("tr", {}, ...["checkpoint", "modified", "accuracy", "wave_off recall", "size", ""].map((h) => el("th", { text: h })))), el("tbody")),
    ),
    el(
      "section",
      { class: "card" },
      el("h2", { text: "Promotion history" }),
      el("button", { type: "button", class: "rollback small", text: "Roll back" }),
      el("table", { class: "history" }, el("thead", {}, el("tr", {}, ...["when", "action", "model", "replaced", "accuracy", "by", "override reason"].map((h) => el("th", { text: h })))), el("tbody")),
    ),
  );
  q("button.rollback").addEventListener("click", rollback);
  if (!document.getElementById("promote-dialog")) {
    document.body.append(el("dialog", { id: "promote-dialog" }, el("h2", { text: "Promote a model" }), el("div", { class: "promote-body" })));
  }
  if (!session.config.training_available) {
    setStatus("No federated runner in this server: runs cannot start.", "warn");
  }
  charts = { loss: makeChart(q("canvas.loss"), "loss"), accuracy: makeChart(q("canvas.accuracy"), "accuracy", 1) };
  offs.push(
    on("training_round", (msg) => {
      if (selected === null) {
        selected = msg.run_id;
        resetCharts(`Run ${msg.run_id}: running`);
      }
      if (msg.run_id === selected) addRound(msg);
    }),
    on("training_run", (msg) => {
      if (msg.run_id === selected) {
        const detail = msg.detail ? ` (${msg.detail})` : "";
        q(".run-title").textContent = `Run ${msg.run_id}: ${msg.status}${detail}`;
      }
      refreshRuns().catch(showError);
      if (msg.status === "completed") refreshModels().catch(showError);
    }),
    on("model", () => refreshModels().catch(showError)),
  );
  refreshRuns().catch(showError);
  refreshModels().catch(showError);
}

export function unmount() {
  for (const off of offs) off();
  offs = [];
  for (const chart of Object.values(charts)) chart.destroy();
  charts = {};
  root = null;
}
