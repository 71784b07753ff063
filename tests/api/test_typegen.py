"""The browser's types are generated from the backend's and kept current; the browser
subscribes to exactly the message types the server sends."""

from __future__ import annotations

import re
from pathlib import Path

from proxima.api import typegen
from proxima.api.hub import MESSAGE_TYPES

FRONTEND = Path(__file__).resolve().parents[2] / "frontend" / "src"


def test_the_generated_types_are_current() -> None:
    assert typegen.OUT == FRONTEND / "types.gen.js"
    assert typegen.OUT.read_text(encoding="utf-8") == typegen.generate(), (
        "frontend/src/types.gen.js is stale: run python -m proxima.api.typegen"
    )
    assert typegen.main(["--check"]) == 0


def test_the_check_fails_on_a_stale_file(tmp_path: Path) -> None:
    stale = tmp_path / "types.gen.js"
    stale.write_text(typegen.generate().replace('"pose"', '"poses"'), encoding="utf-8")
    assert typegen.main(["--check", "--out", str(stale)]) == 1
    assert typegen.main(["--out", str(stale)]) == 0
    assert stale.read_text(encoding="utf-8") == typegen.generate()


def test_the_browser_subscribes_to_what_the_server_sends() -> None:
    subscribed = {
        name
        for path in FRONTEND.rglob("*.js")
        for name in re.findall(r'\bon\(\s*"(\w+)"', path.read_text(encoding="utf-8"))
    }
    assert subscribed == set(MESSAGE_TYPES)


def test_js_types_of_json_schemas() -> None:
    assert typegen.js_type({"anyOf": [{"type": "number"}, {"type": "null"}]}) == "number | null"
    assert typegen.js_type({"type": "array", "prefixItems": [{"type": "number"}] * 2}) == (
        "[number, number]"
    )
    assert typegen.js_type({"type": "array", "items": {"enum": ["a", "b"]}}) == '("a" | "b")[]'
    assert typegen.js_type({"$ref": "#/components/schemas/StreamLive"}) == "StreamLive"
    assert typegen.js_type({"type": "object"}) == "Record<string, any>"
