"""Guarded promotion in the browser (issue 26, finding 1): the Models table shows each
checkpoint's held-out accuracy, promoting a worse model shows both models' figures and
needs an override reason, the Live page names the model in use, and the history rolls
back to the previous model."""

from __future__ import annotations

import shutil
from pathlib import Path

from ui_helpers import laser_clip, login, screenshot, start_console


def test_promotion_is_guarded_shown_on_live_and_rolled_back(  # type: ignore[no-untyped-def]
    page, tmp_path: Path, degraded_checkpoint: Path
) -> None:
    from proxima.gesture.classifier import default_checkpoint

    checkpoint_path = default_checkpoint()
    models = tmp_path / "models"
    (models / "runs").mkdir(parents=True)
    shutil.copy(checkpoint_path, models / "gesture-default.pt")
    shutil.copy(degraded_checkpoint, models / "runs" / "worse.pt")
    console = start_console(
        tmp_path,
        with_engine=True,
        streams=[{"name": "front", "uri": f"replay:{laser_clip('hover_f')}@30", "drone": "main"}],
        engine={"checkpoint": str(models / "gesture-default.pt")},
        server={
            "db_path": str(tmp_path / "c.db"),
            "models_dir": str(models),
            "viser_enabled": False,
        },
        training={"enabled": False},
    )
    try:
        assert console.runtime.engine is not None, console.runtime.notes
        login(page, console.url)
        page.wait_for_selector(".model-in-use .model-name:has-text('gesture-default.pt')")
        assert "configured model" in page.inner_text(".model-in-use")

        page.click("nav a[data-page=training]")
        row = "table.models tr[data-model='runs/worse.pt']"
        # Figures are evaluated on the server, one checkpoint at a time.
        page.wait_for_function(
            f'() => /^0\\.\\d{{3}}$/.test(document.querySelector("{row} .acc")?.textContent)',
            timeout=90000,
        )
        worse_acc = float(page.inner_text(f"{row} .acc"))
        page.wait_for_function(
            "() => /^0\\.\\d{3}$/.test(document.querySelector("
            "\"table.models tr[data-model='gesture-default.pt'] .acc\")?.textContent)",
            timeout=90000,
        )
        in_use_acc = float(page.inner_text("table.models tr[data-model='gesture-default.pt'] .acc"))
        assert worse_acc < in_use_acc - 0.1, (worse_acc, in_use_acc)
        assert (
            page.inner_text("table.models tr[data-model='gesture-default.pt'] button") == "in use"
        )

        page.click(f"{row} button.promote")
        dialog = "#promote-dialog"
        page.wait_for_selector(f"{dialog} table.compare")
        text = page.inner_text(dialog)
        assert "runs/worse.pt" in text and "gesture-default.pt" in text
        assert "This model looks worse" in text and "wave_off" in text
        assert "synthetic" in text
        assert page.is_disabled(f"{dialog} button.confirm-promote")
        page.fill(f"{dialog} textarea.override-reason", "field trial of the new model")
        assert page.is_enabled(f"{dialog} button.confirm-promote")
        screenshot(page, "promotion-guard")
        page.click(f"{dialog} button.confirm-promote")
        page.wait_for_selector(f"{dialog}:not([open])", state="attached")
        page.wait_for_selector(".train-status.ok:has-text('Promoted runs/worse.pt')")
        page.wait_for_selector("table.history td:has-text('field trial of the new model')")
        active = console.runtime.promoter.active_checkpoint()
        assert Path(active).name == "worse.pt"

        page.click("nav a[data-page=live]")
        page.wait_for_selector(".model-in-use .model-name:has-text('runs/worse.pt')")
        assert f"accuracy {worse_acc:.3f}" in page.inner_text(".model-in-use")
        assert "promoted by chief" in page.inner_text(".model-in-use")

        page.click("nav a[data-page=training]")
        page.wait_for_selector("button.rollback:has-text('Roll back to gesture-default.pt')")
        page.once("dialog", lambda d: d.accept())
        page.click("button.rollback")
        page.wait_for_selector(".train-status.ok:has-text('Rolled back')")
        assert Path(console.runtime.promoter.active_checkpoint()).name == "gesture-default.pt"
        page.wait_for_selector("table.history tbody tr:first-child td:has-text('rollback')")
    finally:
        console.close()
