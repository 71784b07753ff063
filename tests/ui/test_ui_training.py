"""The Training page: a supervisor starts a federated run on Flower's deployment engine
(a local SuperLink and one SuperNode per drone, real processes on 127.0.0.1) and sees
its curve points appear, the run starting from the synthetic operator's model; a viewer
who tries the same gets 403."""

from __future__ import annotations

from pathlib import Path

from ui_helpers import VIEWER, login, own_server, screenshot, start_console


def test_start_a_run_and_see_curve_points(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    console = start_console(
        tmp_path,
        server=own_server(tmp_path),
    )
    try:
        assert console.runtime.training is not None, console.runtime.notes
        login(page, console.url)
        page.click("nav a[data-page=training]")
        page.fill("form.start-run input[name=rounds]", "1")
        page.fill("form.start-run input[name=local_epochs]", "1")
        with page.expect_response(
            lambda r: r.url.endswith("/api/training/runs") and r.request.method == "POST"
        ) as response:
            page.click("form.start-run button.start")
        assert response.value.status == 202, response.value.text()
        run_id = response.value.json()["id"]
        page.wait_for_selector(f"table.runs tr[data-run='{run_id}']")
        # The first point (the global model before any round) arrives from the run.
        page.wait_for_function(
            "() => Number(document.querySelector('.chart-points').textContent) > 0",
            timeout=90000,
        )
        page.wait_for_selector(".run-title:has-text('completed')", timeout=120000)
        page.wait_for_function(
            "() => Number(document.querySelector('.chart-points').textContent) >= 2"
        )
        run = console.runtime.training.get_run(run_id)
        assert run["status"] == "completed" and [r["round"] for r in run["rounds"]] == [0, 1]
        # The console's runs start from the synthetic operator's model (`[training] start`):
        # round 0 already names most held-out windows (a fresh model: about 0.08).
        assert run["rounds"][0]["global_accuracy"] > 0.5, run["rounds"][0]
        # The runs table shows how long the run took (m:ss), as the store timed it.
        cell = f"table.runs tr[data-run='{run_id}'] td.duration"
        page.wait_for_function(
            f"() => /^\\d+:\\d\\d$/.test(document.querySelector(\"{cell}\")?.textContent || '')"
        )
        took = int(run["finished_at"] - run["started_at"] + 0.5)  # as Math.round
        assert page.text_content(cell) == f"{took // 60}:{took % 60:02d}"
        page.wait_for_timeout(300)
        screenshot(page, "training")
    finally:
        console.close()


def test_viewer_gets_403_on_starting_a_run(page, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    console = start_console(tmp_path)
    try:
        login(page, console.url, VIEWER)
        page.click("nav a[data-page=training]")
        page.wait_for_selector("form.start-run")
        # The form's bounds and choices are FLConfig's, its values the runner's defaults.
        attrs = page.eval_on_selector_all(
            "form.start-run input[type=number]",
            "els => Object.fromEntries(els.map(e => [e.name, [e.min, e.max, e.step, e.value]]))",
        )
        assert attrs == {
            "rounds": ["1", "500", "1", "5"],
            "local_epochs": ["1", "100", "1", "20"],  # the console's recipe ([training])
            "batch_size": ["1", "4096", "1", "64"],
            "learning_rate": ["0.000001", "1", "any", "0.002"],
            "fraction_fit": ["0", "1", "any", "1"],
            "min_clients": ["1", "3", "1", "2"],  # at most the federation's 3 drones
        }
        strategies = page.eval_on_selector_all(
            "form.start-run select[name=strategy] option", "els => els.map(e => e.value)"
        )
        assert strategies == ["fedavg", "fedprox", "fedadam", "fedavgm", "scaffold"]
        assert page.eval_on_selector("form.start-run select[name=strategy]", "e => e.value") == (
            "scaffold"
        )
        assert page.is_checked("form.start-run input[name=include_samples]")
        with page.expect_response(
            lambda r: r.url.endswith("/api/training/runs") and r.request.method == "POST"
        ) as response:
            page.click("form.start-run button.start")
        assert response.value.status == 403
        page.wait_for_selector(".train-status.error:has-text('Forbidden')")
        assert "viewer" in page.inner_text(".train-status")
        assert console.runtime.training.list_runs() == []
        screenshot(page, "training-viewer-403")
    finally:
        console.close()
