"""The small interfaces the console calls into other subsystems through.

The console only listens to the bus for everything live; actions a supervisor takes go
through these, implemented by the federated runner, the drone link and the live engine.
When one is absent the matching routes answer 503 with the reason, never a pretend
success.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol, runtime_checkable

from proxima.federated.config import FLConfig


@runtime_checkable
class TrainingRunner(Protocol):
    """Starts federated runs and reports them. Runs publish per-round metrics on the bus;
    `get_run` returns what is persisted; `defaults` fills the Training form."""

    @property
    def defaults(self) -> FLConfig:
        """The parameters of a run for every field its request leaves out."""
        ...

    @property
    def clients(self) -> list[str]:
        """The drones (federated clients) a run trains on; `min_clients` may not exceed
        their number."""
        ...

    def start_run(self, params: dict[str, Any]) -> str:
        """Start a run with these parameters; returns its id at once (runs in background).

        Raises:
            ValueError: a bad parameter (named), e.g. more `min_clients` than `clients`.
            RuntimeError: a run is already in progress.
        """
        ...

    def cancel_run(self, run_id: str) -> bool:
        """Ask run `run_id` to stop (it ends as `stopped`); False if it is not running."""
        ...

    def list_runs(self) -> list[dict[str, Any]]:
        """Every run, newest first: id, status, params, started/finished, final accuracy."""
        ...

    def get_run(self, run_id: str) -> dict[str, Any] | None:
        """One run with its per-round and per-client metrics, or None."""
        ...


@runtime_checkable
class EmergencyStop(Protocol):
    """Two-step emergency stop: `request` returns a confirmation id and changes nothing;
    only `confirm` with that id (before it expires) stops the drone."""

    def request(self, drone: str, user: str) -> dict[str, Any]:
        """Returns at least `confirmation_id` and `expires_in_s`.

        Raises:
            KeyError: unknown drone.
        """
        ...

    def confirm(self, drone: str, confirmation_id: str, user: str) -> dict[str, Any]:
        """Stops the drone; returns the outcome (`ok`, `detail`).

        Raises:
            PermissionError: unknown, expired or already used confirmation id.
        """
        ...

    def resume(self, drone: str, user: str) -> dict[str, Any]:
        """Clear a confirmed stop: gesture control may be armed again (have_command).

        Raises:
            KeyError: unknown drone.  ValueError: the drone is not stopped.
        """
        ...


@runtime_checkable
class ModelPromoter(Protocol):
    """Puts a checkpoint into the live engine (an explicit action, never automatic)."""

    def promote(self, checkpoint_path: str, streams: Sequence[str] | None = None) -> dict[str, Any]:
        """Load the checkpoint into every stream's classifier (or `streams`' only);
        returns what was loaded (`streams`, `window`, and `pending`: streams that have
        not switched yet).

        Raises:
            ValueError: the file is not a usable checkpoint, or an unknown stream.
        """
        ...

    def active_checkpoint(self, stream: str | None = None) -> str | None:
        """The model `stream` runs, else the one promoted for every stream."""
        ...
