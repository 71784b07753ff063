"""`proxima fl ...`: federated runs on Flower's simulation and deployment engines, their
curves, promoting a run's model into the live engine, and a fleet's certificates."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any, NoReturn

import typer

fl_app = typer.Typer(
    help="Federated training with Flower: every drone trains on its own data.",
    no_args_is_help=True,
)

Rounds = Annotated[int, typer.Option(help="Federated rounds.")]
DbOpt = Annotated[
    Path | None, typer.Option(help="SQLite database for runs (default: the console's).")
]
# Options `simulate` and `deploy-local` share (None: the run config's default).
JsonOut = Annotated[Path | None, typer.Option("--json", help="Write the run record here.")]
PngOut = Annotated[Path | None, typer.Option(help="Write the learning curve here.")]
LocalEpochs = Annotated[int | None, typer.Option(help="Local epochs a round.")]
Strategy = Annotated[
    str | None, typer.Option(help="fedavg | fedprox | fedadam | fedavgm | scaffold")
]
Partition = Annotated[str | None, typer.Option(help="view | iid | dirichlet")]
MinClients = Annotated[int | None, typer.Option(help="Drones a round needs.")]
Stride = Annotated[int | None, typer.Option(help="Frames between training windows.")]
DataOpt = Annotated[str | None, typer.Option(help="Data folder(s), ';'-separated.")]
SetOpt = Annotated[
    list[str] | None, typer.Option("--set", help="Any run-config key: --set batch-size=32")
]
InitOpt = Annotated[
    Path | None,
    typer.Option(help="Start the global model from this checkpoint (e.g. synthetic pretraining)."),
]
ModelsDir = Annotated[Path | None, typer.Option(help="Where the global model is saved.")]


def _fail(message: str) -> NoReturn:
    typer.secho(f"error: {message}", fg="red", err=True)
    raise typer.Exit(2)


def _settings_paths(db: Path | None, models_dir: Path | None) -> tuple[Path, Path]:
    """The console's database and models folder unless given."""
    if db is not None and models_dir is not None:
        return db, models_dir
    from proxima.settings import Settings, SettingsError

    try:
        server = Settings.load().server
    except SettingsError as exc:
        _fail(str(exc))
    return db or server.db_path, models_dir or server.models_dir


def _config(**values: Any) -> Any:
    from proxima.federated.runner import config_from_params

    sets = values.pop("set_", None) or []
    params = {k: v for k, v in values.items() if v is not None}
    if isinstance(params.get("init"), Path):  # absolute: the ServerApp runs elsewhere
        params["init"] = str(params["init"].resolve())
    for item in sets:
        key, sep, value = item.partition("=")
        if not sep:
            _fail(f"--set {item!r}: expected KEY=VALUE")
        params[key.strip()] = value.strip()
    try:
        return config_from_params(params)
    except ValueError as exc:
        _fail(str(exc))


class _Progress:
    """A rich progress bar over rounds, with each round's global accuracy."""

    def __init__(self, total: int, label: str) -> None:
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        self.progress = Progress(
            TextColumn(f"[bold]{label}[/]"),
            BarColumn(),
            TextColumn("{task.completed}/{task.total}"),
            TextColumn("{task.description}"),
            TimeElapsedColumn(),
        )
        self.task = self.progress.add_task("starting", total=total)

    def round(self, row: dict[str, Any]) -> None:
        acc = row.get("global_accuracy")
        desc = f"round {row['round']}: global accuracy {acc:.3f}" if acc is not None else ""
        self.progress.update(self.task, completed=row["round"], description=desc)
        for c in row["clients"]:
            if c.get("status") != "ok" or c.get("detail"):
                note = f"{c.get('status')} {c.get('detail') or ''}"
                self.progress.console.print(f"  round {row['round']} {c['drone']}: {note}")

    def status(self, status: str, detail: str, _extra: dict[str, Any]) -> None:
        if status in ("waiting", "failed"):
            self.progress.console.print(f"[yellow]{status}[/]: {detail}")
        self.progress.update(self.task, description=f"{status} {detail}"[:80])


def simulate(
    rounds: Rounds = 5,
    json_out: JsonOut = None,
    png: PngOut = None,
    drones: Annotated[int, typer.Option(help="Virtual drones (SuperNodes).")] = 3,
    local_epochs: LocalEpochs = None,
    strategy: Strategy = None,
    partition: Partition = None,
    min_clients: MinClients = None,
    stride: Stride = None,
    seed: Annotated[int | None, typer.Option()] = None,
    data: DataOpt = None,
    init: InitOpt = None,
    set_: SetOpt = None,
    db: DbOpt = None,
    models_dir: ModelsDir = None,
    save: Annotated[bool, typer.Option(help="Save the global model and its card.")] = True,
) -> None:
    """Run on Flower's simulation engine (one process; a virtual SuperNode per drone)."""
    from proxima.federated.simulate import simulate as run_sim
    from proxima.store.training import TrainingStore

    cfg = _config(rounds=rounds, num_drones=drones, local_epochs=local_epochs, strategy=strategy,
                  partition=partition, min_clients=min_clients, stride=stride, seed=seed,
                  data=data, init=init, set_=set_)  # fmt: skip
    db_path, models = _settings_paths(db, models_dir)
    cfg.models_dir = str(models) if save else ""
    store = TrainingStore(db_path)
    bar = _Progress(cfg.rounds, "simulate")
    with bar.progress:
        try:
            result = run_sim(cfg, store=store, on_round=bar.round, on_status=bar.status)
        except RuntimeError as exc:
            _fail(str(exc))
    _report(result.to_json(), json_out, png, f"{cfg.strategy}, {cfg.partition}")


def _report(out: dict[str, Any], json_out: Path | None, png: Path | None, what: str) -> None:
    """Write the run record and its learning curve, print the summary; exit 1 unless the
    run completed."""
    if json_out is not None:
        json_out.parent.mkdir(parents=True, exist_ok=True)
        json_out.write_text(json.dumps(out, indent=1))
    if png is not None:
        from proxima.federated.curve import plot_curve

        plot_curve(out["rounds"], png, f"run {out['run_id']} ({what})")
    _summary(out, json_out, png)
    if out["status"] != "completed":
        raise typer.Exit(1)


def _summary(out: dict[str, Any], json_out: Path | None, png: Path | None) -> None:
    acc = out.get("final_accuracy")
    typer.echo(
        f"run {out['run_id']}: {out['status']}, {len(out['rounds']) - 1} rounds, global accuracy "
        f"{acc if acc is None else round(acc, 3)}, {out['wall_s']:.1f} s"
        + (f", model {out['checkpoint']}" if out.get("checkpoint") else "")
        + (f" -> {json_out}" if json_out else "")
        + (f", {png}" if png else "")
        + (f" ({out['detail']})" if out.get("detail") and out["status"] != "completed" else "")
    )


def deploy_local(
    rounds: Rounds = 5,
    json_out: JsonOut = None,
    png: PngOut = None,
    drones: Annotated[int, typer.Option(help="SuperNodes to start (one per drone).")] = 3,
    local_epochs: LocalEpochs = None,
    strategy: Strategy = None,
    partition: Partition = None,
    min_clients: MinClients = None,
    stride: Stride = None,
    data: DataOpt = None,
    init: InitOpt = None,
    set_: SetOpt = None,
    db: DbOpt = None,
    models_dir: ModelsDir = None,
    workdir: Annotated[Path | None, typer.Option(help="Logs and Flower state.")] = None,
    insecure: Annotated[
        bool, typer.Option(help="No TLS and no SuperNode keys (loopback only; to compare).")
    ] = False,
) -> None:
    """Run on Flower's deployment engine: a SuperLink and one SuperNode per drone as
    separate processes on 127.0.0.1 (TLS and SuperNode authentication with a throwaway
    CA unless --insecure), the run submitted with `flwr run`."""
    from proxima.federated.deploy import DeploymentError
    from proxima.federated.pki import PKIError
    from proxima.federated.runner import FederatedRunner
    from proxima.federated.settings import DeploymentSettings

    cfg = _config(rounds=rounds, num_drones=drones, local_epochs=local_epochs, strategy=strategy,
                  partition=partition, min_clients=min_clients, stride=stride, data=data,
                  init=init, set_=set_)  # fmt: skip
    db_path, models = _settings_paths(db, models_dir)
    security = DeploymentSettings(tls=not insecure, supernode_auth=not insecure)
    runner = FederatedRunner(db_path, models, workdir=workdir, defaults=cfg, security=security)
    bar = _Progress(cfg.rounds, "deploy-local")
    from proxima.federated.events import TrainingRoundEvent, TrainingRunEvent

    def on_event(ev: Any) -> None:
        if isinstance(ev, TrainingRoundEvent):
            bar.round({"round": ev.round, "global_accuracy": ev.global_accuracy,
                       "clients": list(ev.clients)})  # fmt: skip
        elif isinstance(ev, TrainingRunEvent):
            bar.status(ev.status, ev.detail, {})

    runner.listeners.append(on_event)
    try:
        with bar.progress:
            bar.progress.console.print("starting the SuperLink and SuperNodes on 127.0.0.1 ...")
            try:
                runner.ensure_federation()
            except (DeploymentError, PKIError) as exc:
                _fail(str(exc))
            st = runner.status()
            how = (
                "TLS, SuperNode keys"
                if st["supernode_auth"]
                else "TLS"
                if st["tls"]
                else "insecure"
            )
            bar.progress.console.print(f"SuperLink {st['superlink']} ({how}), PIDs {st['pids']}")
            run_id = runner.start_run({})
            run = runner.wait()
    finally:
        runner.close()
    assert run is not None
    out = {"run_id": run_id, "engine": "deployment", "status": run["status"],
           "detail": run["detail"], "rounds": run["rounds"],
           "final_accuracy": run["final_accuracy"], "checkpoint": run["checkpoint"],
           "model_card": run["model_card"], "flwr_run_id": run["flwr_run_id"],
           "wall_s": (run["finished_at"] or 0) - (run["started_at"] or 0),
           "config": run["params"]}  # fmt: skip
    _report(out, json_out, png, f"deployment, {cfg.strategy}")


def curve(
    run: Annotated[str, typer.Argument(help="Run id (see `proxima fl runs`).")],
    png: Annotated[Path, typer.Option(help="Where to write the PNG.")],
    db: DbOpt = None,
) -> None:
    """Plot a run's learning curve (global and per-drone accuracy and loss per round)."""
    from proxima.federated.curve import plot_curve
    from proxima.store.training import TrainingStore

    db_path, _ = _settings_paths(db, Path("."))
    record = TrainingStore(db_path).get_run(run)
    if record is None:
        _fail(f"no run {run!r} in {db_path}")
    plot_curve(record["rounds"], png, f"run {run} ({record['engine']}, {record['status']})")
    typer.echo(f"{png}")


def runs(db: DbOpt = None) -> None:
    """List federated runs, newest first."""
    from proxima.store.training import TrainingStore

    db_path, _ = _settings_paths(db, Path("."))
    for r in TrainingStore(db_path).list_runs():
        acc = r["final_accuracy"]
        typer.echo(
            f"{r['id']}  {r['engine']:<10} {r['status']:<9} {r['rounds_done']}/{r['rounds_total']} "
            f"rounds  accuracy {'-' if acc is None else f'{acc:.3f}'}  {r['checkpoint'] or ''}"
        )


def promote(
    run: Annotated[str, typer.Argument(help="Run id whose global model goes live.")],
    url: Annotated[str, typer.Option(help="The running console.")] = "http://127.0.0.1:8000",
    user: Annotated[str, typer.Option(envvar="PROXIMA_USER", help="Supervisor account.")] = "",
    password: Annotated[
        str, typer.Option(envvar="PROXIMA_PASSWORD", prompt=True, hide_input=True)
    ] = "",
    db: DbOpt = None,
    models_dir: Annotated[Path | None, typer.Option(help="The console's models folder.")] = None,
    override_reason: Annotated[
        str,
        typer.Option(
            help="Why to promote a model whose held-out figures are below the minimum or "
            "the model in use's (the console refuses it otherwise; audited)."
        ),
    ] = "",
) -> None:
    """Put a run's global model into the live engine of a running console (an explicit
    supervisor action, through the console's API; nothing is promoted automatically)."""
    import httpx

    from proxima.store.training import TrainingStore

    db_path, models = _settings_paths(db, models_dir)
    store = TrainingStore(db_path)
    record = store.run_row(run)
    if record is None:
        _fail(f"no run {run!r} in {db_path}")
    ckpt = Path(record["checkpoint"] or "")
    if not record["checkpoint"] or not ckpt.is_file():
        _fail(f"run {run} has no checkpoint (status {record['status']})")
    try:
        name = str(ckpt.resolve().relative_to(models.resolve()))
    except ValueError:
        _fail(f"{ckpt} is not inside the console's models folder {models}")
    try:
        with httpx.Client(base_url=url, timeout=30) as client:
            login = client.post("/api/auth/login", json={"username": user, "password": password})
            if login.status_code != 200:
                _fail(f"login to {url} as {user!r} failed: {login.status_code} {login.text}")
            token = login.json().get("token", "")
            body = {"override_reason": override_reason} if override_reason else None
            res = client.post(f"/api/models/{name}/promote", json=body,
                              headers={"Authorization": f"Bearer {token}"})  # fmt: skip
    except httpx.HTTPError as exc:
        _fail(f"no console at {url}: {exc}")
    if res.status_code != 200:
        _fail(f"promotion refused: {res.status_code} {res.text}")
    store.update_run(run, promoted_at=__import__("time").time())
    typer.echo(f"promoted {name} (run {run}) into the live engine at {url}")


def pki(
    out: Annotated[Path, typer.Argument(help="Folder of the fleet's certificates and keys.")],
    host: Annotated[
        list[str] | None,
        typer.Option(
            help="Address the drones dial (IP or host name; repeat for more). "
            "Makes the ground station's certificate."
        ),
    ] = None,
    drone: Annotated[
        list[str] | None, typer.Option(help="A drone's name (repeat): its SuperNode key pair.")
    ] = None,
) -> None:
    """Make a fleet's CA, the ground station's TLS certificate and the drones' SuperNode
    keys (an existing CA and existing drone keys are kept), and say what goes where."""
    from proxima.federated.pki import PKIError, make_ca, make_drone_key, make_server_cert

    if not host and not drone and (out / "ca" / "ca.crt").is_file():
        _fail("nothing to do: give --host and/or --drone")
    ca_cert, ca_key = out / "ca" / "ca.crt", out / "ca" / "ca.key"
    try:
        if not ca_cert.is_file():
            make_ca(out / "ca")
            typer.echo(f"made the CA: {ca_cert} (keep {ca_key} offline, never on a drone)")
        if host:
            creds = make_server_cert(out / "ground", ca_cert, ca_key, host)
            typer.echo(f"ground station: {creds.cert} for {', '.join(host)}, 127.0.0.1; "
                       f"key {creds.key}")  # fmt: skip
        for name in drone or []:
            folder = out / "drones" / name
            if (folder / f"{name}.key").exists():
                typer.echo(f"drone {name}: key kept ({folder / f'{name}.key'})")
            else:
                key = make_drone_key(folder, name)
                typer.echo(f"drone {name}: {key.private_key} (stays on the drone)")
            (folder / "ca.crt").write_bytes(ca_cert.read_bytes())
            pub = out / "ground" / "authorized" / f"{name}.pub"
            pub.parent.mkdir(parents=True, exist_ok=True)
            pub.write_bytes((folder / f"{name}.pub").read_bytes())
    except PKIError as exc:
        _fail(str(exc))
    typer.echo(
        f"copy {out / 'ground'} to the ground station ([training] ca_certfile, "
        f"server_certfile, server_keyfile, authorized_keys), and {out / 'drones'}/NAME to "
        "drone NAME's companion computer (docs/federated.md, 'A real fleet')"
    )


def register(app: typer.Typer) -> None:
    fl_app.command()(simulate)
    fl_app.command("deploy-local")(deploy_local)
    fl_app.command()(curve)
    fl_app.command()(runs)
    fl_app.command()(promote)
    fl_app.command()(pki)
    app.add_typer(fl_app, name="fl")
