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

Chart.register(LineController, LineElement, PointElement, LinearScale, Legend, Tooltip);

const COLORS = ["#4fc3f7", "#ffb74d", "#81c784", "#e57373", "#ba68c8", "#fff176", "#90a4ae"];
let root = null;
let charts = {};
let selected = null; // run id shown in the charts
let offs = [];

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
  resetCharts(`Run ${id}: ${run.status || ""}`);
  for (const r of run.rounds || []) addRound(r);
}

async function refreshRuns() {
  const runs = await api("/training/runs");
  if (selected === null && runs.length) showRun(runs[0].id);
  q("table.runs tbody").replaceChildren(
    ...runs.map((r) => {
      const tr = el(
        "tr",
        { "data-run": r.id },
        el("td", { text: String(r.id) }),
        el("td", { class: "status", text: r.status || "" }),
        el("td", { text: r.started_at ? new Date(r.started_at * 1000).toLocaleString() : "" }),
        el("td", { text: String(r.params?.rounds ?? r.rounds_total ?? "") }),
        el("td", { text: typeof r.final_accuracy === "number" ? r.final_accuracy.toFixed(3) : "" }),
        el("td", { text: r.checkpoint ? r.checkpoint.split("/").pop() : "" }),
      );
      tr.addEventListener("click", () => showRun(r.id));
      return tr;
    }),
  );
}

async function refreshModels() {
  const res = await api("/models");
  q("table.models tbody").replaceChildren(
    ...res.models.map((m) => {
      const btn = el("button", { class: "promote small", text: m.active ? "active" : "promote" });
      btn.disabled = m.active || !isSupervisor() || !res.promotion_available;
      btn.addEventListener("click", async () => {
        try {
          await api(`/models/${m.name.split("/").map(encodeURIComponent).join("/")}/promote`, { method: "POST" });
          setStatus(`Promoted ${m.name} to the live engine.`, "ok");
          refreshModels();
        } catch (err) {
          setStatus(err.message, "error");
        }
      });
      return el(
        "tr",
        { "data-model": m.name },
        el("td", { text: m.name }),
        el("td", { text: new Date(m.modified * 1000).toLocaleString() }),
        el("td", { text: `${Math.round(m.size_bytes / 1024)} KiB` }),
        el("td", {}, btn),
      );
    }),
  );
}

function setStatus(text, cls = "") {
  const s = q(".train-status");
  s.textContent = text;
  s.className = `train-status ${cls}`;
}

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
  for (const [name, spec] of formFields()) {
    if (spec.type === "boolean") body[name] = f.get(name) === "on";
    else if (spec.enum) body[name] = f.get(name);
    else body[name] = Number(f.get(name));
  }
  try {
    const res = await api("/training/runs", { method: "POST", body });
    setStatus(`Run ${res.id} started.`, "ok");
    selected = res.id;
    resetCharts(`Run ${res.id}: starting`);
    refreshRuns();
  } catch (err) {
    setStatus(`${err.status === 403 ? "Forbidden: " : ""}${err.message}`, "error");
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
    { class: "card start-run" },
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
      el("table", { class: "runs" }, el("thead", {}, el("tr", {}, ...["id", "status", "started", "rounds", "accuracy", "checkpoint"].map((h) => el("th", { text: h })))), el("tbody")),
    ),
    el(
      "section",
      { class: "card" },
      el("h2", { text: "Models" }),
      el("table", { class: "models" }, el("thead", {}, el("tr", {}, ...["checkpoint", "modified", "size", ""].map((h) => el("th", { text: h })))), el("tbody")),
    ),
  );
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
      refreshRuns();
      if (msg.status === "completed") refreshModels();
    }),
  );
  refreshRuns().catch((err) => setStatus(err.message, "error"));
  refreshModels().catch((err) => setStatus(err.message, "error"));
}

export function unmount() {
  for (const off of offs) off();
  offs = [];
  for (const chart of Object.values(charts)) chart.destroy();
  charts = {};
  root = null;
}
