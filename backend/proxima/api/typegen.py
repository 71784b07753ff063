"""The browser's types, generated from the backend's: `python -m proxima.api.typegen`.

Writes `frontend/src/types.gen.js`: JSDoc typedefs of every WebSocket message (the bus
events of `proxima.events.EVENT_TYPES` the hub forwards, its `stream_live` and `hello`)
and of the HTTP API's schemas (FastAPI's OpenAPI of the routers), plus `MESSAGE_TYPES`,
the names `ws.js` lets a page subscribe to. `npm run build` type-checks the console's
modules that say `// @ts-check` against them (tsc), and `tests/api/test_typegen.py`
fails while the file differs from what this module generates; `--check` does the same
from the command line.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from fastapi import FastAPI
from pydantic import TypeAdapter

from proxima.api.hub import MESSAGE_TYPES
from proxima.api.live import StreamLiveMessage
from proxima.api.schemas import Hello
from proxima.events import EVENT_TYPES

OUT = Path(__file__).resolve().parents[3] / "frontend" / "src" / "types.gen.js"
_REF = "#/components/schemas/"

Schema = dict[str, Any]


def _openapi_schemas() -> tuple[dict[str, Schema], set[str]]:
    """The API's component schemas and the names used as request bodies."""
    from proxima.api.app import ROUTERS  # the app module builds no app on import

    app = FastAPI(title="Proxima console")
    for router in ROUTERS:
        app.include_router(router, prefix="/api")
    spec = app.openapi()
    # FastAPI's own 422 body: the browser only shows its `detail` as text (api.js).
    schemas = spec["components"]["schemas"]
    for name in ("HTTPValidationError", "ValidationError"):
        schemas.pop(name, None)
    inputs: set[str] = set()
    for ops in spec["paths"].values():
        for op in ops.values():
            body = json.dumps(op.get("requestBody", {}))
            inputs.update(part.split('"')[0] for part in body.split(_REF)[1:])
    return dict(schemas), inputs


def _message_schemas() -> tuple[dict[str, Schema], dict[str, str]]:
    """The WebSocket messages' schemas (and those they refer to), and each message
    type's schema name."""
    defs: dict[str, Schema] = {}
    names: dict[str, str] = {}
    kinds: dict[str, Any] = {"hello": Hello, StreamLiveMessage.type: StreamLiveMessage}
    kinds.update({name: cls for name, cls in EVENT_TYPES.items() if name in MESSAGE_TYPES})
    for kind in MESSAGE_TYPES:
        cls = kinds[kind]
        schema = TypeAdapter(cls).json_schema(mode="serialization", ref_template=_REF + "{model}")
        for name, sub in schema.pop("$defs", {}).items():
            _merge(defs, name, sub)
        _merge(defs, cls.__name__, schema)
        names[kind] = cls.__name__
    return defs, names


def _merge(defs: dict[str, Schema], name: str, schema: Schema) -> None:
    schema = {k: v for k, v in schema.items() if k != "title"}
    if name in defs and _plain(defs[name]) != _plain(schema):
        raise ValueError(f"two different schemas are named {name!r}")
    defs.setdefault(name, schema)


def _plain(schema: Any) -> Any:
    """`schema` without titles, descriptions and defaults (which differ between how
    FastAPI and a TypeAdapter describe one type)."""
    if isinstance(schema, dict):
        skip = {"title", "description", "default"}
        return {k: _plain(v) for k, v in schema.items() if k not in skip}
    if isinstance(schema, list):
        return [_plain(v) for v in schema]
    return schema


def js_type(schema: Schema) -> str:
    """A JSON schema as a TypeScript type expression (what JSDoc's braces take).

    Raises:
        ValueError: a `$ref` outside the components (nothing here makes one).
    """
    if "$ref" in schema:
        ref = schema["$ref"]
        if not ref.startswith(_REF):
            raise ValueError(f"unexpected $ref {ref!r}")
        return ref[len(_REF) :]
    if "const" in schema:
        return json.dumps(schema["const"])
    if "enum" in schema:
        return " | ".join(json.dumps(v) for v in schema["enum"])
    for union in ("anyOf", "oneOf"):
        if union in schema:
            return " | ".join(dict.fromkeys(js_type(s) for s in schema[union]))
    kind = schema.get("type")
    if isinstance(kind, list):
        return " | ".join(js_type({**schema, "type": k}) for k in kind)
    if kind in ("integer", "number"):
        return "number"
    if kind in ("string", "boolean", "null"):
        return str(kind)
    if kind == "array":
        if "prefixItems" in schema:
            return "[" + ", ".join(js_type(s) for s in schema["prefixItems"]) + "]"
        item = js_type(schema["items"]) if "items" in schema else "unknown"
        return f"({item})[]" if " | " in item else f"{item}[]"
    if kind == "object":
        if "properties" in schema:
            props = ", ".join(
                f"{k}{'' if k in schema.get('required', ()) else '?'}: {js_type(v)}"
                for k, v in schema["properties"].items()
            )
            return "{" + props + "}"
        extra = schema.get("additionalProperties", True)
        return f"Record<string, {js_type(extra) if isinstance(extra, dict) else 'any'}>"
    return "any"


def _comment(lines: Iterable[str]) -> list[str]:
    return ["/**", *(f" * {line}".rstrip() for line in lines), " */"]


def _doc(schema: Schema) -> list[str]:
    text = str(schema.get("description", "")).replace("*/", "*\\/")
    return [line.strip() for line in text.splitlines()] if text else []


def _typedef(name: str, schema: Schema, all_present: bool) -> list[str]:
    """One schema as a JSDoc typedef. `all_present`: every property is in every value
    (what the server sends: pydantic and `Event.to_dict` write defaults too)."""
    if "properties" not in schema:
        return _comment([*_doc(schema), f"@typedef {{{js_type(schema)}}} {name}"])
    lines = [*_doc(schema), f"@typedef {{object}} {name}"]
    required = set(schema["properties"]) if all_present else set(schema.get("required", ()))
    for prop, sub in schema["properties"].items():
        label = prop if prop in required else f"[{prop}]"
        note = str(sub.get("description", "")).replace("\n", " ")
        lines.append(f"@property {{{js_type(sub)}}} {label}{' ' + note if note else ''}")
    return _comment(lines)


def generate() -> str:
    """The text of `types.gen.js`.

    Raises:
        ValueError: two different schemas share a name.
    """
    api, inputs = _openapi_schemas()
    messages, message_names = _message_schemas()
    defs = dict(api)
    for name, schema in messages.items():
        _merge(defs, name, schema)
    for cls in EVENT_TYPES.values():  # an event's `type` is a plain field, a constant
        if cls.__name__ in defs:
            defs[cls.__name__]["properties"]["type"] = {"const": cls.type}
    out = [
        "// Generated by `python -m proxima.api.typegen` from the event registry",
        "// (proxima.events.EVENT_TYPES), the hub's messages and the API's schemas: do not",
        "// edit; regenerate. tests/api/test_typegen.py fails while this file is stale.",
        "",
        "/** Every `type` the server sends on /api/ws. */",
        "export const MESSAGE_TYPES = Object.freeze([",
        *(f"  {json.dumps(kind)}," for kind in MESSAGE_TYPES),
        "]);",
        "",
        *_comment(
            [
                "`ts` of a message: the wall time (Unix seconds) the hub took it from the bus.",
                "@typedef {object} Stamped",
                "@property {number} ts",
            ]
        ),
        *_comment(
            [
                "Each message type and what a message of it holds.",
                "@typedef {{",
                *(
                    f"  {json.dumps(kind)}: {name}{'' if kind == 'hello' else ' & Stamped'},"
                    for kind, name in message_names.items()
                ),
                "}} MessageMap",
            ]
        ),
        "/** @typedef {MessageMap[keyof MessageMap]} Message */",
        "",
    ]
    for name in sorted(defs):
        out += [*_typedef(name, defs[name], all_present=name not in inputs), ""]
    return "\n".join(out[:-1]) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m proxima.api.typegen", description=__doc__)
    parser.add_argument(
        "--out", type=Path, default=OUT, help="file to write (default: %(default)s)"
    )
    parser.add_argument("--check", action="store_true", help="only say whether it is stale")
    args = parser.parse_args(argv)
    text = generate()
    current = args.out.read_text(encoding="utf-8") if args.out.is_file() else None
    if args.check:
        if current != text:
            print(f"{args.out} is stale: run python -m proxima.api.typegen", file=sys.stderr)
            return 1
        return 0
    if current != text:
        args.out.write_text(text, encoding="utf-8")
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
